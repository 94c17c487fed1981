// The depth cameras: a ray per pixel cast against the DART world as it is now.
//
// Boxes, cylinders and spheres (every shape of the scene's objects and of the project's
// URDFs) are intersected exactly, in the shape's own frame. Bullet's ray test (DART's
// BulletCollisionDetector::raycast) is used only for other shapes (meshes): on this
// scene's boxes its convex cast was off by up to 9 mm on slanted rays, where the camera
// must be within a fraction of a millimetre. Either way the cameras read the world and
// never touch the simulation's collision detector or state: the physics and its digest
// are the same with or without cameras.
#include <cmath>
#include <dart/collision/CollisionGroup.hpp>
#include <dart/collision/CollisionObject.hpp>
#include <dart/collision/RaycastOption.hpp>
#include <dart/collision/RaycastResult.hpp>
#include <dart/collision/bullet/BulletCollisionDetector.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/BoxShape.hpp>
#include <dart/dynamics/CylinderShape.hpp>
#include <dart/dynamics/ShapeNode.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/dynamics/SphereShape.hpp>
#include <algorithm>
#include <limits>

#include "physics_impl.hpp"

namespace skillbus::sim {

using scene::SceneError;
using Eigen::Vector3d;

namespace {

constexpr double kNone = std::numeric_limits<double>::infinity();

// The nearest t in [t_min, t_max] where o + t d (local frame) enters the shape.
double ray_box(const Vector3d& o, const Vector3d& d, const Vector3d& half, double t_min, double t_max) {
  double t0 = t_min, t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (std::abs(o[k]) > half[k]) return kNone;
      continue;
    }
    double a = (-half[k] - o[k]) / d[k], b = (half[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return kNone;
  }
  return t0;
}

double ray_sphere(const Vector3d& o, const Vector3d& d, double r, double t_min, double t_max) {
  const double b = o.dot(d), c = o.squaredNorm() - r * r, disc = b * b - c;  // (|d| = 1)
  if (disc < 0) return kNone;
  const double s = std::sqrt(disc);
  for (double t : {-b - s, -b + s})
    if (t >= t_min && t <= t_max) return t;
  return kNone;
}

// DART's cylinder: axis z, centred on its frame.
double ray_cylinder(const Vector3d& o, const Vector3d& d, double r, double h, double t_min, double t_max) {
  double best = kNone;
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a > 0) {
    const double b = o.x() * d.x() + o.y() * d.y(), c = o.x() * o.x() + o.y() * o.y() - r * r, disc = b * b - a * c;
    if (disc >= 0) {
      const double s = std::sqrt(disc);
      for (double t : {(-b - s) / a, (-b + s) / a})
        if (t >= t_min && t <= t_max && std::abs(o.z() + t * d.z()) <= 0.5 * h) best = std::min(best, t);
    }
  }
  if (d.z() != 0)
    for (double z : {-0.5 * h, 0.5 * h}) {
      const double t = (z - o.z()) / d.z();
      if (t < t_min || t > t_max) continue;
      const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
      if (x * x + y * y <= r * r) best = std::min(best, t);
    }
  return best;
}

// One shape as a ray sees it this capture: where it is, and a sphere around it that a
// ray must pass through first.
struct Target {
  enum Kind { kBox, kCylinder, kSphere } kind;
  bool robot;  // a shape of a robot's links
  Eigen::Isometry3d to_local;
  Vector3d size;  // box: half extents; cylinder: radius, height; sphere: radius
  Vector3d centre;
  double radius;
};

std::vector<Target> targets_of(const std::vector<dart::dynamics::SkeletonPtr>& skeletons,
                               const std::vector<dart::dynamics::SkeletonPtr>& robots,
                               dart::collision::CollisionGroup* others) {
  using namespace dart::dynamics;
  std::vector<Target> out;
  for (const auto& s : skeletons)
    for (size_t b = 0; b < s->getNumBodyNodes(); ++b)
      for (auto* sn : s->getBodyNode(b)->getShapeNodesWith<CollisionAspect>()) {
        const auto& shape = sn->getShape();
        Target t{};
        if (auto* box = dynamic_cast<const BoxShape*>(shape.get())) {
          t.kind = Target::kBox;
          t.size = 0.5 * box->getSize();
          t.radius = t.size.norm();
        } else if (auto* cyl = dynamic_cast<const CylinderShape*>(shape.get())) {
          t.kind = Target::kCylinder;
          t.size = Vector3d(cyl->getRadius(), cyl->getHeight(), 0);
          t.radius = std::hypot(cyl->getRadius(), 0.5 * cyl->getHeight());
        } else if (auto* sph = dynamic_cast<const SphereShape*>(shape.get())) {
          t.kind = Target::kSphere;
          t.size = Vector3d(sph->getRadius(), 0, 0);
          t.radius = sph->getRadius();
        } else {
          if (others) others->addShapeFrame(sn);
          continue;
        }
        t.robot = std::find(robots.begin(), robots.end(), s) != robots.end();
        const Eigen::Isometry3d T = sn->getWorldTransform();
        t.to_local = T.inverse();
        t.centre = T.translation();
        out.push_back(t);
      }
  return out;
}

// The nearest hit along the unit ray o + t d, t in [t_min, t_max] (kNone: none), and
// whether it is on a robot.
double cast(const std::vector<Target>& targets, const Vector3d& o, const Vector3d& d, double t_min, double t_max,
            bool& on_robot) {
  double best = t_max;
  bool hit = false;
  for (const Target& g : targets) {
    // Skip a shape whose bounding sphere the ray misses (or meets only beyond the best).
    const Vector3d oc = g.centre - o;
    const double along = oc.dot(d);
    if ((oc - along * d).squaredNorm() > g.radius * g.radius || along + g.radius < t_min || along - g.radius > best)
      continue;
    const Vector3d lo = g.to_local * o, ld = g.to_local.linear() * d;
    double t = kNone;
    switch (g.kind) {
      case Target::kBox: t = ray_box(lo, ld, g.size, t_min, best); break;
      case Target::kCylinder: t = ray_cylinder(lo, ld, g.size.x(), g.size.y(), t_min, best); break;
      case Target::kSphere: t = ray_sphere(lo, ld, g.size.x(), t_min, best); break;
    }
    if (t <= best) {
      best = t;
      hit = true;
      on_robot = g.robot;
    }
  }
  return hit ? best : kNone;
}

}  // namespace

void Physics::Impl::build_cameras() {
  cameras.clear();
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    const scene::CameraSpec& spec = scene.cameras[i];
    CameraRig rig;
    rig.spec = &spec;
    rig.mount = to_iso(spec.pose);
    if (!spec.robot.empty()) {
      for (size_t r = 0; r < scene.robots.size(); ++r)
        if (scene.robots[r].name == spec.robot) rig.link = world.robots[r]->getBodyNode(spec.link);
      if (rig.link == nullptr)
        throw SceneError(scene.path + ": cameras[" + std::to_string(i) + "].link names '" + spec.link +
                         "', which robot '" + spec.robot + "' does not have");
    }
    cameras.push_back(rig);
  }
}

DepthCapture Physics::capture(size_t camera, int64_t capture_index) {
  if (camera >= impl_->cameras.size())
    throw std::out_of_range("camera " + std::to_string(camera) + ": the scene has " +
                            std::to_string(impl_->cameras.size()));
  const CameraRig& rig = impl_->cameras[camera];
  const scene::CameraSpec& c = *rig.spec;
  const Eigen::Isometry3d T = rig.link ? Eigen::Isometry3d(rig.link->getWorldTransform() * rig.mount) : rig.mount;
  DepthCapture out;
  out.camera = c.name;
  out.width = c.width;
  out.height = c.height;
  out.intrinsics = {c.fx, c.fy, c.cx, c.cy};
  out.near = c.near;
  out.far = c.far;
  from_iso(T, out.pose.data());
  out.xyz.assign(static_cast<size_t>(c.width) * c.height * 3, std::numeric_limits<float>::quiet_NaN());

  // The shapes where they are now; the ones without an exact intersection go to Bullet.
  auto detector = dart::collision::BulletCollisionDetector::create();
  auto others = detector->createCollisionGroup();
  const std::vector<Target> targets = targets_of(impl_->world.all, impl_->world.robots, others.get());
  out.on_robot.assign(static_cast<size_t>(c.width) * c.height, 0);
  const bool use_bullet = others->getNumShapeFrames() > 0;
  const dart::collision::RaycastOption closest(false, false);
  dart::collision::RaycastResult hit;

  const Vector3d origin = T.translation();
  for (int v = 0; v < c.height; ++v) {
    for (int u = 0; u < c.width; ++u) {
      // Pixel centres at whole coordinates (OpenCV's convention for the intrinsics).
      const Vector3d dir = Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0).normalized();
      const Vector3d world_dir = T.linear() * dir;
      // From the near plane on: a mounted camera's own link (the ray starts inside it)
      // is never in the way.
      bool on_robot = false;
      double range = cast(targets, origin, world_dir, c.near, c.far, on_robot);
      if (use_bullet) {
        hit.clear();
        if (detector->raycast(others.get(), origin + c.near * world_dir, origin + c.far * world_dir, closest, &hit) &&
            hit.hasHit()) {
          const double r = c.near + hit.mRayHits.front().mFraction * (c.far - c.near);
          if (r < range) {
            range = r;
            const auto* sn = hit.mRayHits.front().mCollisionObject->getShapeFrame()->asShapeNode();
            const auto skel = sn ? sn->getSkeleton() : nullptr;
            on_robot = skel && std::find(impl_->world.robots.begin(), impl_->world.robots.end(), skel) !=
                                   impl_->world.robots.end();
          }
        }
      }
      if (!std::isfinite(range)) continue;
      const int64_t pixel = static_cast<int64_t>(v) * c.width + u;
      if (c.noise_stddev_m > 0) range += c.noise_stddev_m * ray_noise(c.seed, capture_index, pixel);
      if (range < c.near || range > c.far) continue;
      const Vector3d p = range * dir;
      for (int k = 0; k < 3; ++k) out.xyz[pixel * 3 + k] = static_cast<float>(p[k]);
      out.on_robot[pixel] = on_robot;
      ++out.returns;
    }
  }
  return out;
}

size_t Physics::num_cameras() const { return impl_->cameras.size(); }

}  // namespace skillbus::sim
