// The 3D view: the scene's bodies (boxes, cylinders, spheres; shapes from /api/scene3d)
// posed per frame by the server (x y z qx qy qz qw per body), the tool's planned path as
// a line, bodies in contact with a finger lit red. three.js is Debian's (libjs-three),
// served by the console at /vendor/three: no CDN.
"use strict";

class View3D {
  constructor(container, replay) {
    this.container = container;
    this.replay = replay;
    this.bodies = new Map();
    this.ready = this.init();
  }

  async init() {
    if (typeof THREE === "undefined") {
      this.container.textContent = "three.js is missing: install Debian's libjs-three (make setup does).";
      return false;
    }
    const spec = await (await fetch(`/api/scene3d?replay=${this.replay ? 1 : 0}`)).json();
    const w = this.container.clientWidth || 800, h = this.container.clientHeight || 500;
    try {
      this.renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
    } catch (e) {
      this.container.textContent = `no WebGL in this browser: ${e.message}`;
      return false;
    }
    this.renderer.setSize(w, h);
    this.renderer.setClearColor(0xf0f2f5);
    this.container.replaceChildren(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(45, w / h, 0.01, 50);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(1.5, 1.7, 1.3);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 0.9));
    const sun = new THREE.DirectionalLight(0xffffff, 0.6);
    sun.position.set(1, -1, 2);
    this.scene.add(sun);
    const grid = new THREE.GridHelper(2, 20, 0x9999aa, 0xccccdd);
    grid.rotation.x = Math.PI / 2;
    this.scene.add(grid);
    this.controls = THREE.OrbitControls ? new THREE.OrbitControls(this.camera, this.renderer.domElement) : null;
    if (this.controls) { this.controls.target.set(0.25, 0.25, 0.2); this.controls.update();
                         this.controls.addEventListener("change", () => this.draw()); }
    else this.camera.lookAt(0.25, 0.25, 0.2);
    for (const b of spec.bodies) {
      const group = new THREE.Group();
      const material = new THREE.MeshLambertMaterial({color: b.color});
      for (const s of b.shapes) {
        let g;
        if (s.kind === "box") g = new THREE.BoxGeometry(s.size[0], s.size[1], s.size[2]);
        else if (s.kind === "cylinder") { g = new THREE.CylinderGeometry(s.size[0], s.size[0], s.size[1], 24);
                                          g.rotateX(Math.PI / 2); }   // URDF cylinders lie along z
        else g = new THREE.SphereGeometry(s.size[0], 16, 12);
        const mesh = new THREE.Mesh(g, material);
        setPose(mesh, s.origin);
        group.add(mesh);
      }
      if (b.pose) setPose(group, b.pose);
      group.userData = {material, color: b.color, role: b.role};
      this.scene.add(group);
      this.bodies.set(b.body, group);
    }
    this.path = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({color: 0xe67e22}));
    this.scene.add(this.path);
    this.draw();
    return true;
  }

  async show(frame) {
    if (!(await this.ready) || !frame) return;
    for (const [name, pose] of Object.entries(frame.poses)) {
      const g = this.bodies.get(name);
      if (g) setPose(g, pose);
    }
    const held = new Set(frame.held || []);
    for (const [name, g] of this.bodies) g.userData.material.emissive.setHex(held.has(name) ? 0x661111 : 0x000000);
    const pts = (frame.path || []).map(p => new THREE.Vector3(p[0], p[1], p[2]));
    this.path.geometry.dispose();
    this.path.geometry = new THREE.BufferGeometry().setFromPoints(pts);
    this.draw();
  }

  draw() { if (this.renderer) this.renderer.render(this.scene, this.camera); }
}

function setPose(obj, p) {
  obj.position.set(p[0], p[1], p[2]);
  obj.quaternion.set(p[3], p[4], p[5], p[6]);
}

function contactsText(frame) {
  if (!frame) return "no physics state";
  const c = frame.contacts.map(c => `${c.a}–${c.b} ${c.force} N`).join(", ");
  return `frame ${frame.frame} · ${frame.sim_time_s.toFixed(2)} s · fingers ${frame.finger_width_mm} mm apart · ` +
         (c ? `contacts: ${c}` : "no contacts");
}
