// The skillbus console's page: skills (start form), tasks (live trees, commands) and the
// world model (tree, element editor, search). One WebSocket brings what happens
// (/api/live: a snapshot, then changes of trees by node); HTTP does the rest.
"use strict";

const $ = (sel, root = document) => root.querySelector(sel);
const el = (tag, attrs = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null) e.setAttribute(k, v);
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
};

function say(text, error = false) {
  const m = $("#message");
  m.textContent = text;
  m.className = error ? "error" : "";
  m.hidden = !text;
}

async function api(method, path, body) {
  const r = await fetch(path, {method, headers: body ? {"Content-Type": "application/json"} : {},
                               body: body ? JSON.stringify(body) : undefined});
  let data = null;
  try { data = await r.json(); } catch (e) { data = {error: `${r.status} ${r.statusText}`}; }
  if (!r.ok) throw new Error((data && (data.error || data.detail)) || `${r.status}`);
  return data;
}

// ---- pages ------------------------------------------------------------------
const pages = {skills: loadSkills, tasks: () => {}, world: loadWorld, view3d: showLive3d, replay: showReplay};
function show(page) {
  for (const b of document.querySelectorAll("header nav button")) b.classList.toggle("active", b.dataset.page === page);
  for (const p of document.querySelectorAll(".page")) p.hidden = p.id !== `page-${page}`;
  location.hash = page;
  pages[page]();
}
for (const b of document.querySelectorAll("header nav button")) b.addEventListener("click", () => show(b.dataset.page));

// ---- skills -------------------------------------------------------------------
let skills = [];
async function loadSkills() {
  try { skills = await api("GET", "/api/skills"); } catch (e) { say(`skills: ${e.message}`, true); return; }
  const list = $("#skill-list");
  list.replaceChildren();
  let robot = null;
  for (const s of skills) {
    if (s.robot !== robot) {
      robot = s.robot;
      list.append(el("div", {class: "robot"}, `robot ${robot || "(none)"} · ${s.manager}`));
    }
    if (s.error) { list.append(el("p", {class: "hint bad", "data-error": s.robot}, s.error)); continue; }
    list.append(el("div", {class: "item", "data-skill": s.type, "data-robot": s.robot, onclick: () => skillForm(s)},
                   s.type, el("small", {}, `${s.compound ? "compound" : "primitive"} · ${s.label}`)));
  }
  if (!skills.some(s => !s.error)) list.append(el("p", {class: "hint"}, "No skill manager answered (yet)."));
}

function defaultText(p) {
  if (!p.defaults.length) return "";
  const v = p.defaults[0];
  if (v && typeof v === "object" && "id" in v) return v.id || "";
  return typeof v === "string" ? v : JSON.stringify(v);
}

async function elementPicker(p) {
  const sel = el("select", {name: p.key, "data-param": p.key});
  sel.append(el("option", {value: ""}, p.kind === "Required" ? "(choose)" : "(none)"));
  try {
    const found = await api("GET", `/api/world/search?type=${encodeURIComponent(p.concept || "")}`);
    for (const e of found) sel.append(el("option", {value: e.id}, `${e.id}${e.label ? " · " + e.label : ""}`));
  } catch (e) { sel.append(el("option", {value: "", disabled: ""}, `(world model: ${e.message})`)); }
  const d = defaultText(p);
  if (d) sel.value = d;
  return sel;
}

async function skillForm(s) {
  for (const i of document.querySelectorAll("#skill-list .item")) i.classList.toggle("selected",
    i.dataset.skill === s.type && i.dataset.robot === s.robot);
  const form = el("form", {class: "params", "data-testid": "start-form"});
  for (const p of s.params) {
    const input = p.data_type === "element" ? await elementPicker(p)
      : el("input", {name: p.key, "data-param": p.key, value: defaultText(p),
                     placeholder: p.data_type});
    form.append(el("label", {}, el("span", {}, `${p.key} `, el("small", {},
      `${p.data_type}${p.concept ? " " + p.concept : ""}, ${p.kind}`)), input,
      p.description ? el("small", {class: "muted"}, ` ${p.description}`) : null));
  }
  form.append(el("button", {type: "submit", "data-testid": "start"}, `Start ${s.type}`));
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const params = {};
    for (const p of s.params) {
      const v = form.elements[p.key].value;
      if (v !== "" && v !== defaultText(p)) params[p.key] = v;
    }
    try {
      const r = await api("POST", "/api/tasks", {robot: s.robot, skill: s.type, label: s.label, params});
      say(`task ${r.task} started: ${s.type}`);
      selected = key(r.robot, r.task);
      show("tasks");
      renderTaskList();
      renderTree();
    } catch (e) { say(`start ${s.type}: ${e.message}`, true); }
  });
  const cond = (name, cs) => cs.map(c => el("div", {}, `${name}: ${c.label}: ${c.desired_state ? "" : "not "}` +
                                                       `${c.kind} ${c.owl} ${c.subject} ${c.object}`));
  $("#skill-form").replaceChildren(el("h2", {}, `${s.type} `, el("small", {class: "muted"},
    `${s.label} on robot ${s.robot || "(none)"}`)), form,
    el("div", {class: "conditions"}, ...cond("pre", s.pre), ...cond("hold", s.hold), ...cond("post", s.post)));
}

// ---- tasks ---------------------------------------------------------------------
const tasks = new Map();   // "robot#task" -> {robot, task, state, tick, nodes, ...}
let selected = null;
const key = (robot, task) => `${robot}#${task}`;

function applyChange(c) {
  const k = key(c.robot, c.task);
  let t = tasks.get(k);
  // (new: the first tree of this task, or another task of the same number: a restarted manager's)
  if (!t || c.new) { t = {robot: c.robot, task: c.task, nodes: [], tick: -1}; tasks.set(k, t); }
  if (c.tick < t.tick || t.ended) return false;   // older than what is shown
  for (const n of c.nodes) t.nodes[n.id] = n;
  t.nodes.length = c.count;
  Object.assign(t, {state: c.state, tick: c.tick, ended: c.ended || c.state === "Success" || c.state === "Failure"});
  return true;
}

// The list is rebuilt only when its order changes (a new task, an end); otherwise the
// task's own row is updated in place (a row replaced at every tick could not be clicked).
let listOrder = null;
function taskItem(t) {
  const item = el("div", {class: "item", "data-task": t.task, "data-robot": t.robot,
                          onclick: () => { selected = key(t.robot, t.task); renderTaskList(); renderTree(); }});
  updateTaskItem(item, t);
  return item;
}
function updateTaskItem(item, t) {
  item.classList.toggle("selected", key(t.robot, t.task) === selected);
  item.dataset.state = t.state;
  item.replaceChildren(el("span", {class: `state ${t.state}`}, t.state), `${t.nodes[0] ? t.nodes[0].type : "?"} `,
    el("small", {}, `task ${t.task}${t.robot ? " · " + t.robot : ""} · tick ${t.tick}`));
}
function renderTaskList(only) {
  const list = $("#task-list");
  const sorted = [...tasks.values()].sort((a, b) => (a.ended - b.ended) || (b.task - a.task) ||
                                                    a.robot.localeCompare(b.robot));
  const order = sorted.map(t => key(t.robot, t.task)).join(",");
  if (order === listOrder && only) {
    const t = tasks.get(only);
    const item = [...list.children].find(i => key(i.dataset.robot, Number(i.dataset.task)) === only);
    if (t && item) { updateTaskItem(item, t); return; }
  }
  if (order === listOrder && !only) {
    for (const item of list.children) {
      const t = tasks.get(key(item.dataset.robot, Number(item.dataset.task)));
      if (t) updateTaskItem(item, t);
    }
    return;
  }
  listOrder = order;
  list.replaceChildren(...sorted.map(taskItem));
  if (!tasks.size) list.append(el("p", {class: "hint"}, "No task yet."));
}

function nodeRow(n, depth) {
  const params = Object.entries(n.params || {}).map(([k, v]) => `${k}=${v}`).join("\n");
  return el("div", {class: "node", "data-node": n.id, "data-state": n.state, style: `padding-left:${depth * 1.3}em`},
    el("span", {class: `state ${n.state}`}, n.state),
    el("span", {class: "name"}, n.type || `(${n.processor})`),
    n.processor && n.type ? el("small", {class: "muted"}, `[${n.processor}]`) : null,
    n.message ? el("span", {class: "msg"}, n.message) : null,
    n.progress ? el("small", {class: "muted"}, `${Math.round(n.progress * 100)}%`) : null,
    params ? el("div", {class: "params"}, params) : null);
}

// Rows are kept by node id and replaced one by one as changes arrive (ids are pre-order
// positions: a row's place in the list is its id).
function renderTree(change) {
  const t = selected && tasks.get(selected);
  const tree = $("#task-tree");
  if (!t) { tree.replaceChildren(); $("#task-head").replaceChildren(el("p", {class: "hint"}, "Pick a task.")); return; }
  $("#task-head").replaceChildren(el("h2", {}, `task ${t.task}: ${t.nodes[0] ? t.nodes[0].type : "?"} `,
    el("span", {class: `state ${t.state}`, "data-testid": "task-state", "data-tick": t.tick}, t.state),
    el("small", {class: "muted"}, ` robot ${t.robot || "(none)"} · tick ${t.tick}`)));
  const depth = [];
  t.nodes.forEach((n, i) => { depth[i] = n && n.parent >= 0 ? depth[n.parent] + 1 : 0; });
  const ids = change ? change.nodes.map(n => n.id) : t.nodes.map((_, i) => i);
  if (!change || tree.dataset.task !== selected) tree.replaceChildren();
  tree.dataset.task = selected;
  for (const i of ids) {
    const row = nodeRow(t.nodes[i], depth[i]);
    if (tree.children[i]) tree.children[i].replaceWith(row); else tree.append(row);
  }
  while (tree.children.length > t.nodes.length) tree.lastChild.remove();
}

for (const b of document.querySelectorAll(".controls button")) {
  b.addEventListener("click", async () => {
    const t = selected && tasks.get(selected);
    if (!t) { say("pick a task first", true); return; }
    try {
      const r = await api("POST", `/api/tasks/${t.task}/${b.dataset.verb}?robot=${encodeURIComponent(t.robot)}`);
      say(`task ${t.task}: ${r.message}`);
    } catch (e) { say(`${b.dataset.verb} task ${t.task}: ${e.message}`, true); }
  });
}

// ---- live ------------------------------------------------------------------------
function connect() {
  const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/api/live`);
  ws.onopen = () => { $("#connection").textContent = "live"; $("#connection").className = "good"; };
  ws.onclose = () => { $("#connection").textContent = "reconnecting"; $("#connection").className = "bad";
                       setTimeout(connect, 1000); };
  ws.onmessage = (m) => {
    const ev = JSON.parse(m.data);
    if (ev.kind === "hello") {
      tasks.clear();
      listOrder = null;
      for (const t of ev.tasks) applyChange({...t, count: t.nodes.length, nodes: t.nodes.map((n, i) => ({...n, id: i}))});
      renderTaskList(); renderTree();
    } else if (ev.kind === "tree") {
      if (applyChange(ev)) {
        renderTaskList(key(ev.robot, ev.task));
        if (selected === key(ev.robot, ev.task)) renderTree(ev);
      }
    } else if (ev.kind === "managers") {
      if (!$("#page-skills").hidden) loadSkills();
    } else if (ev.kind === "world") {
      worldVersion = ev.version;
      if (!$("#page-world").hidden) scheduleWorldReload();
    } else if (ev.kind === "sim") {
      if (live3d && !$("#page-view3d").hidden) { live3d.show(ev); $("#live-contacts").textContent = contactsText(ev); }
    } else if (ev.kind === "overflow") {
      say(ev.message, true);
    }
  };
}

// ---- world model -------------------------------------------------------------------
let worldVersion = -1, worldTimer = null, shownElement = null;
function scheduleWorldReload() {
  if (worldTimer) return;
  worldTimer = setTimeout(() => { worldTimer = null; loadTree(); }, 1000);
}

async function loadWorld() { await loadTree(); }

async function loadTree() {
  let t;
  try { t = await api("GET", "/api/world/tree"); } catch (e) { say(`world model: ${e.message}`, true); return; }
  const item = (n, depth) => [el("div", {class: "item" + (n.id === shownElement ? " selected" : ""), "data-element": n.id,
      style: `padding-left:${depth * 1.2 + .5}em`, onclick: () => showElement(n.id)},
    n.id, el("small", {}, n.label || "")), ...n.children.flatMap(c => item(c, depth + 1))];
  $("#world-tree").replaceChildren(el("small", {class: "muted"}, `version ${t.version}`),
                                   ...t.roots.flatMap(r => item(r, 0)));
  if (shownElement) markStale();
}

function markStale() {
  const e = $("#element [data-testid=element-version]");
  if (e && worldVersion > Number(e.dataset.version))
    e.textContent = `read at version ${e.dataset.version}; the world is at ${worldVersion} (an edit of a changed element is refused)`;
}

$("#world-reload").addEventListener("click", () => { loadTree(); if (shownElement) showElement(shownElement); });
$("#world-search").addEventListener("submit", async (ev) => {
  ev.preventDefault();
  const f = ev.target;
  try {
    const found = await api("GET", `/api/world/search?type=${encodeURIComponent(f.type.value)}&label=${encodeURIComponent(f.label.value)}`);
    $("#search-results").replaceChildren(el("small", {class: "muted"}, `${found.length} found`),
      ...found.map(e => el("div", {class: "item", "data-element": e.id, onclick: () => showElement(e.id)}, e.id,
                          el("small", {}, `${e.label} · ${e.type}`))));
  } catch (e) { say(`search: ${e.message}`, true); }
});

function valueText(p) { return p.values.length === 1 ? String(p.values[0]) : JSON.stringify(p.values); }
function textValues(text, single) {
  if (!single || text.trim().startsWith("[")) { try { const v = JSON.parse(text); if (Array.isArray(v)) return v; } catch (e) {} }
  return [text];
}

async function edit(body, what) {
  try {
    const r = await api("POST", "/api/world/edit", body);
    say(`${what}: done (world version ${r.version})`);
    const id = body.op === "remove" ? null : (body.id || (r.ids && r.ids[0]));
    loadTree();
    if (id) showElement(id); else $("#element").replaceChildren(el("p", {class: "hint"}, "Removed."));
  } catch (e) { say(`${what}: ${e.message}`, true); }
}

async function showElement(id) {
  let e;
  try { e = await api("GET", `/api/world/element/${encodeURIComponent(id)}`); } catch (err) { say(err.message, true); return; }
  shownElement = id;
  for (const i of document.querySelectorAll("#world-tree .item")) i.classList.toggle("selected", i.dataset.element === id);
  const read = e.read;
  const label = el("input", {value: e.label, "data-testid": "label-input"});
  const rows = e.properties.map(p => {
    const input = el("input", {value: valueText(p), "data-prop": p.key, size: 30});
    return el("tr", {}, el("td", {}, p.key), el("td", {class: "muted"}, p.type), el("td", {}, input),
      el("td", {}, el("button", {"data-save": p.key, onclick: () => edit({op: "set_property", id, read, key: p.key,
        values: textValues(input.value, p.values.length === 1)}, `set ${p.key} of ${id}`)}, "Save"),
        el("button", {onclick: () => edit({op: "set_property", id, read, key: p.key, values: []}, `remove ${p.key}`)}, "×")));
  });
  const newKey = el("input", {placeholder: "skiros:Key"}), newType = el("select", {},
    ...["float", "int", "string", "bool"].map(t => el("option", {value: t}, t))), newVal = el("input", {placeholder: "value"});
  const rels = e.relations.map(([s, p, o]) => el("div", {"data-relation": `${s} ${p} ${o}`},
    el("a", {href: "#world", onclick: () => showElement(s === id ? o : s)}, `${s} ${p} ${o}`), " ",
    el("button", {onclick: () => edit({op: "unrelate", id, read, subject: s, predicate: p, object: o},
                                      `remove relation ${p}`)}, "×")));
  const relPred = el("input", {placeholder: "skiros:contain"}), relObj = el("input", {placeholder: "object id"});
  const childType = el("input", {placeholder: "skiros:Cube"}), childLabel = el("input", {placeholder: "label"});
  $("#element").replaceChildren(
    el("h2", {}, e.id, " ", el("small", {class: "muted"}, e.type)),
    el("div", {class: "muted", "data-testid": "element-version", "data-version": e.version}, `read at version ${e.version}`),
    el("h3", {}, "Label"),
    el("div", {}, label, " ", el("button", {"data-testid": "save-label",
      onclick: () => edit({op: "set_label", id, read, label: label.value}, `label of ${id}`)}, "Save")),
    el("h3", {}, "Properties"), el("table", {class: "props", "data-testid": "properties"}, ...rows),
    el("div", {}, newKey, newType, newVal, " ", el("button", {onclick: () => edit({op: "set_property", id, read,
      key: newKey.value, type: newType.value, values: [newVal.value]}, `add ${newKey.value}`)}, "Add property")),
    el("h3", {}, "Relations"), el("div", {"data-testid": "relations"}, ...rels),
    el("div", {}, `${id} `, relPred, relObj, " ", el("button", {onclick: () => edit({op: "relate", id, read,
      subject: id, predicate: relPred.value, object: relObj.value}, "relate")}, "Relate")),
    el("h3", {}, "Add an element in it"),
    el("div", {}, childType, childLabel, " ", el("button", {onclick: () => edit({op: "add", type: childType.value,
      label: childLabel.value, parent: id}, `add ${childType.value}`)}, "Add")),
    el("h3", {}, "Remove"),
    el("button", {"data-testid": "remove-element", onclick: () => { if (confirm(`Remove ${id} and its relations?`))
      edit({op: "remove", id, read}, `remove ${id}`); }}, `Remove ${id}`));
}

// ---- 3D (live) -------------------------------------------------------------------------
let live3d = null;
async function showLive3d() {
  if (!live3d) live3d = new View3D($("#live-3d"), false);
  try { const f = await api("GET", "/api/sim"); live3d.show(f); $("#live-contacts").textContent = contactsText(f); }
  catch (e) { $("#live-contacts").textContent = e.message; }
}

// ---- replay --------------------------------------------------------------------------------
let replay3d = null, replayTimer = null, replayWanted = null;
async function showReplay() {
  try { showReplaySummary(await api("GET", "/api/replay")); } catch (e) { /* no log open yet */ }
}

function showReplaySummary(s) {
  const missing = Object.entries(s.missing || {}).map(([c, n]) => `${n} on ${c}`).join(", ");
  $("#replay-summary").replaceChildren(
    el("div", {}, `${s.file}: ${s.frames} frames, ${s.sim_time_s.toFixed(2)} s of sim time, ${s.tasks} task(s)`),
    el("div", {class: "digest", "data-testid": "replay-digest"}, `session digest ${s.digest}`),
    missing ? el("div", {class: "muted"}, `the log lacks messages the clocks announced (${missing}): ` +
                                           "this digest cannot equal the run's") : null,
    s.scene_note ? el("div", {class: "muted"}, s.scene_note) : null);
  const t = $("#timeline");
  t.min = s.first; t.max = s.last; t.disabled = false;
  if (!replay3d) replay3d = new View3D($("#replay-3d"), true);
  replayFrame(Number(t.value));
}

$("#replay-open").addEventListener("submit", async (ev) => {
  ev.preventDefault();
  say("reading the log ...");
  try {
    const s = await api("POST", "/api/replay/open", {path: ev.target.path.value});
    replay3d = null;
    $("#timeline").value = s.first;
    showReplaySummary(s);
    say(`opened ${s.file}`);
  } catch (e) { say(`replay: ${e.message}`, true); }
});

$("#timeline").addEventListener("input", () => replayFrame(Number($("#timeline").value)));

// One frame request at a time; while one is under way only the latest wish waits.
async function replayFrame(frame) {
  replayWanted = frame;
  if (replayTimer) return;
  replayTimer = true;
  while (replayWanted !== null) {
    const f = replayWanted;
    replayWanted = null;
    try { renderReplay(await api("GET", `/api/replay/frame/${f}`)); } catch (e) { say(`replay: ${e.message}`, true); }
  }
  replayTimer = null;
}

function renderReplay(r) {
  $("#replay-frame").replaceChildren(el("b", {"data-testid": "replay-frame-number", "data-frame": r.frame,
                                              "data-asked": r.asked}, `frame ${r.frame}`),
                                     ` · ${r.sim_time_s.toFixed(2)} s`,
                                     r.asked !== r.frame ? ` (frame ${r.asked} is not in the log: the nearest before it)` : "");
  const item = (n, depth, parent) => [el("div", {class: "item", "data-element": n.id, "data-parent": parent,
      style: `padding-left:${depth * 1.2 + .5}em`}, n.id, el("small", {}, n.label || "")),
    ...n.children.flatMap(c => item(c, depth + 1, n.id))];
  $("#replay-world").replaceChildren(...r.world.flatMap(n => item(n, 0, "")));
  const rows = [];
  for (const t of r.tasks) {
    rows.push(el("div", {class: "robot"}, `task ${t.task}${t.robot ? " · " + t.robot : ""}: ${t.skill} ${t.state} · tick ${t.tick}`));
    const depth = [];
    t.nodes.forEach((n, i) => { depth[i] = n.parent >= 0 ? depth[n.parent] + 1 : 0; rows.push(nodeRow(n, depth[i])); });
  }
  $("#replay-tasks").replaceChildren(...rows);
  $("#replay-contacts").textContent = contactsText(r.sim);
  if (replay3d && r.sim) replay3d.show(r.sim);
}

// ---- start ----------------------------------------------------------------------------
connect();
const first = (location.hash || "#skills").slice(1);
show(first in pages ? first : "skills");
