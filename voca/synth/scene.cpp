#include "voca/synth/scene.h"

#include <cmath>
#include <limits>
#include <numbers>

namespace voca::synth {

namespace {

constexpr float kMinT = 1e-4f;  // ignore hits closer than this (the origin's own surface)

enum class Kind { kWall, kBox, kCylinderSide, kCylinderCap, kDisc };

struct Candidate {
  float t = std::numeric_limits<float>::infinity();
  Kind kind = Kind::kWall;
  int index = 0;
  int face = 0;
};

// Uniform draws from a hash chain, for the scene layout.
class HashRng {
 public:
  explicit HashRng(std::uint32_t seed) : state_(hash32(seed ^ 0x5ce7e5u)) {}
  float uniform(float lo, float hi) {
    state_ = hash32(state_ + 0x9e3779b9u);
    return lo + (hi - lo) * unitFloat(state_);
  }
  std::uint32_t next() {
    state_ = hash32(state_ + 0x9e3779b9u);
    return state_;
  }

 private:
  std::uint32_t state_;
};

// Distance from p to a vertical cylinder-shaped bound (centre c, radius r, half height hz).
double boundDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& c, double r, double hz) {
  const double horizontal = std::max(0.0, std::hypot(p.x() - c.x(), p.y() - c.y()) - r);
  const double vertical = std::max(0.0, std::abs(p.z() - c.z()) - hz);
  return std::hypot(horizontal, vertical);
}

bool clearOf(std::span<const Eigen::Vector3d> keep_out, const Eigen::Vector3d& c, double r, double hz, double margin) {
  for (const Eigen::Vector3d& p : keep_out) {
    if (boundDistance(p, c, r, hz) < margin) return false;
  }
  return true;
}

}  // namespace

Scene::Scene(const RoomBox& room) : room_(room), room_min_(room.min.cast<float>()), room_max_(room.max.cast<float>()) {}

int Scene::addMaterial(const TextureParams& params) {
  materials_.emplace_back(params);
  return static_cast<int>(materials_.size()) - 1;
}

void Scene::setWallMaterial(int wall, int material) { wall_material_[wall] = material; }

void Scene::addBox(const BoxObject& box) {
  boxes_.push_back(box);
  box_cos_sin_.emplace_back(std::cos(box.yaw), std::sin(box.yaw));
  box_radius2_.push_back(box.half_size.squaredNorm());
}

bool Scene::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, Hit& hit) const {
  Candidate best;
  // Room: the exit through each pair of slabs; the nearest is the wall the ray meets.
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0.0f) continue;
    const bool positive = dir[a] > 0.0f;
    const float t = ((positive ? room_max_[a] : room_min_[a]) - origin[a]) / dir[a];
    if (t < best.t) best = {t, Kind::kWall, 2 * a + (positive ? 1 : 0), a};
  }

  for (std::size_t k = 0; k < boxes_.size(); ++k) {
    const BoxObject& box = boxes_[k];
    const Eigen::Vector3f d = origin - box.center;
    // Bounding sphere: most rays miss most boxes, and this rejects them in a few operations
    // (the line misses the sphere, the sphere is behind the origin, or beyond the nearest hit so far).
    const float r2 = box_radius2_[k];
    const float along = -d.dot(dir);
    const float dist2 = d.squaredNorm();
    if (dist2 - along * along > r2) continue;
    if (along < 0.0f && dist2 > r2) continue;
    if (along > best.t && (along - best.t) * (along - best.t) > r2) continue;
    const float cs = box_cos_sin_[k].x();
    const float sn = box_cos_sin_[k].y();
    const Eigen::Vector3f lo(cs * d.x() + sn * d.y(), -sn * d.x() + cs * d.y(), d.z());
    const Eigen::Vector3f ld(cs * dir.x() + sn * dir.y(), -sn * dir.x() + cs * dir.y(), dir.z());
    float t_near = -std::numeric_limits<float>::infinity();
    float t_far = std::numeric_limits<float>::infinity();
    int near_axis = 0;
    bool miss = false;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(ld[a]) < 1e-12f) {
        if (std::abs(lo[a]) > box.half_size[a]) miss = true;
        continue;
      }
      const float inv = 1.0f / ld[a];
      float t0 = (-box.half_size[a] - lo[a]) * inv;
      float t1 = (box.half_size[a] - lo[a]) * inv;
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > t_near) {
        t_near = t0;
        near_axis = a;
      }
      t_far = std::min(t_far, t1);
    }
    if (miss || t_near > t_far || t_near < kMinT || t_near >= best.t) continue;
    best = {t_near, Kind::kBox, static_cast<int>(k), 2 * near_axis + (ld[near_axis] > 0.0f ? 0 : 1)};
  }

  for (std::size_t k = 0; k < cylinders_.size(); ++k) {
    const CylinderObject& cyl = cylinders_[k];
    const float lx = origin.x() - cyl.center_xy.x();
    const float ly = origin.y() - cyl.center_xy.y();
    const float a = dir.x() * dir.x() + dir.y() * dir.y();
    const float b = lx * dir.x() + ly * dir.y();
    const float c = lx * lx + ly * ly - cyl.radius * cyl.radius;
    if (a > 1e-12f && c > 0.0f) {
      const float disc = b * b - a * c;
      if (disc >= 0.0f) {
        const float t = (-b - std::sqrt(disc)) / a;
        const float z = origin.z() + t * dir.z();
        if (t > kMinT && t < best.t && z >= cyl.z0 && z <= cyl.z1)
          best = {t, Kind::kCylinderSide, static_cast<int>(k), 0};
      }
    }
    // Caps, seen from above (top) or below (bottom).
    if (dir.z() != 0.0f) {
      const bool from_above = origin.z() > cyl.z1 && dir.z() < 0.0f;
      const bool from_below = origin.z() < cyl.z0 && dir.z() > 0.0f;
      if (from_above || from_below) {
        const float t = ((from_above ? cyl.z1 : cyl.z0) - origin.z()) / dir.z();
        const float px = lx + t * dir.x();
        const float py = ly + t * dir.y();
        if (t > kMinT && t < best.t && px * px + py * py <= cyl.radius * cyl.radius) {
          best = {t, Kind::kCylinderCap, static_cast<int>(k), from_above ? 0 : 1};
        }
      }
    }
  }

  for (std::size_t k = 0; k < discs_.size(); ++k) {
    const DiscObject& disc = discs_[k];
    const float denom = dir.dot(disc.normal);
    if (std::abs(denom) < 1e-9f) continue;
    const float t = (disc.center - origin).dot(disc.normal) / denom;
    if (t < kMinT || t >= best.t) continue;
    if ((origin + t * dir - disc.center).squaredNorm() <= disc.radius * disc.radius) {
      best = {t, Kind::kDisc, static_cast<int>(k), 0};
    }
  }

  if (!std::isfinite(best.t)) return false;

  // Attributes of the winning surface only.
  hit.t = best.t;
  hit.point = origin + best.t * dir;
  const int num_boxes = static_cast<int>(boxes_.size());
  const int num_cylinders = static_cast<int>(cylinders_.size());
  switch (best.kind) {
    case Kind::kWall: {
      const int wall = best.index;
      const int axis = best.face;
      hit.normal = Eigen::Vector3f::Zero();
      hit.normal[axis] = (wall % 2 == 1) ? -1.0f : 1.0f;
      const int ua = axis == 0 ? 1 : 0;
      const int va = axis == 2 ? 1 : 2;
      hit.u = hit.point[ua];
      hit.v = hit.point[va];
      hit.surface = wall;
      hit.material = wall_material_[wall];
      break;
    }
    case Kind::kBox: {
      const BoxObject& box = boxes_[best.index];
      const float cs = box_cos_sin_[best.index].x();
      const float sn = box_cos_sin_[best.index].y();
      const int axis = best.face / 2;
      const float sign = (best.face % 2 == 0) ? -1.0f : 1.0f;  // face 2a: ray entered through -a
      Eigen::Vector3f n_local = Eigen::Vector3f::Zero();
      n_local[axis] = sign;
      hit.normal =
          Eigen::Vector3f(cs * n_local.x() - sn * n_local.y(), sn * n_local.x() + cs * n_local.y(), n_local.z());
      const Eigen::Vector3f d = hit.point - box.center;
      const Eigen::Vector3f lp(cs * d.x() + sn * d.y(), -sn * d.x() + cs * d.y(), d.z());
      const int ua = axis == 0 ? 1 : 0;
      const int va = axis == 2 ? 1 : 2;
      // Offsets so that the six faces show different parts of the texture.
      hit.u = lp[ua] + 3.7f * static_cast<float>(best.face) + 11.0f * static_cast<float>(best.index);
      hit.v = lp[va] + 1.9f * static_cast<float>(best.face);
      hit.surface = 6 + 6 * best.index + best.face;
      hit.material = box.material;
      break;
    }
    case Kind::kCylinderSide: {
      const CylinderObject& cyl = cylinders_[best.index];
      const float lx = hit.point.x() - cyl.center_xy.x();
      const float ly = hit.point.y() - cyl.center_xy.y();
      hit.normal = Eigen::Vector3f(lx, ly, 0.0f) / cyl.radius;
      const float angle = std::atan2(ly, lx);
      // Arc length keeps the texture undistorted; the seam at +-pi (and the split at 0) are
      // surface changes, so the renderer anti-aliases them like any other edge.
      hit.u = angle * cyl.radius;
      hit.v = hit.point.z();
      hit.surface = 6 + 6 * num_boxes + 3 * best.index + (angle >= 0.0f ? 0 : 1);
      hit.material = cyl.material;
      break;
    }
    case Kind::kCylinderCap: {
      const CylinderObject& cyl = cylinders_[best.index];
      hit.normal = Eigen::Vector3f(0.0f, 0.0f, best.face == 0 ? 1.0f : -1.0f);
      hit.u = hit.point.x() + 7.0f;
      hit.v = hit.point.y();
      hit.surface = 6 + 6 * num_boxes + 3 * best.index + 2;
      hit.material = cyl.material;
      break;
    }
    case Kind::kDisc: {
      const DiscObject& disc = discs_[best.index];
      hit.normal = disc.normal.dot(dir) < 0.0f ? disc.normal : Eigen::Vector3f(-disc.normal);
      hit.u = 0.0f;
      hit.v = 0.0f;
      hit.surface = 6 + 6 * num_boxes + 3 * num_cylinders + best.index;
      hit.material = -1;
      hit.albedo = disc.albedo;
      break;
    }
  }
  return true;
}

float Scene::radiance(const Hit& hit, float footprint_m) const {
  const float albedo = hit.material < 0 ? hit.albedo : materials_[hit.material].sample(hit.u, hit.v, footprint_m);
  float shading = ambient_;
  for (const PointLight& light : lights_) {
    const Eigen::Vector3f to_light = light.position - hit.point;
    const float dist2 = to_light.squaredNorm();
    const float cos_incidence = hit.normal.dot(to_light) / std::sqrt(dist2);
    if (cos_incidence <= 0.0f) continue;
    shading += light.intensity * cos_incidence / (1.0f + dist2 / (light.falloff_m * light.falloff_m));
  }
  return 255.0f * albedo * shading;
}

Scene Scene::generate(const SceneConfig& config, std::span<const Eigen::Vector3d> keep_out, std::uint32_t seed) {
  Scene scene(config.room);
  HashRng rng(seed);
  const RoomBox& room = config.room;

  // Walls: posters and tiles (rectangles), stains (blobs), notices (text), plaster (noise).
  for (int wall = 0; wall < 4; ++wall) {
    TextureParams p;
    p.seed = rng.next();
    p.base = rng.uniform(0.42f, 0.62f);
    p.noise_amp = rng.uniform(0.16f, 0.26f);
    p.noise_max_wavelength_m = rng.uniform(0.6f, 1.0f);
    p.noise_min_wavelength_m = 0.0015f;
    p.noise_persistence = rng.uniform(0.7f, 0.82f);
    p.rect_cell_m = rng.uniform(0.6f, 1.1f);
    p.rect_density = rng.uniform(0.45f, 0.7f);
    p.rect_small_cell_m = rng.uniform(0.12f, 0.25f);
    p.rect_small_density = rng.uniform(0.12f, 0.3f);
    p.blob_cell_m = rng.uniform(0.2f, 0.45f);
    p.blob_density = rng.uniform(0.15f, 0.35f);
    p.text_block_m = rng.uniform(0.004f, 0.008f);
    p.text_line_cell_m = rng.uniform(0.5f, 0.8f);
    p.text_density = rng.uniform(0.25f, 0.45f);
    scene.setWallMaterial(wall, scene.addMaterial(p));
  }
  {
    TextureParams floor;  // speckled tiles
    floor.seed = rng.next();
    floor.base = 0.36f;
    floor.noise_amp = 0.3f;
    floor.noise_max_wavelength_m = 1.0f;
    floor.noise_min_wavelength_m = 0.0015f;
    floor.noise_persistence = 0.85f;
    floor.rect_cell_m = 0.5f;
    floor.rect_density = 0.5f;
    floor.rect_small_cell_m = 0.09f;
    floor.rect_small_density = 0.25f;
    floor.blob_cell_m = 0.3f;
    floor.blob_density = 0.5f;
    scene.setWallMaterial(4, scene.addMaterial(floor));
    TextureParams ceiling;  // panels with fittings
    ceiling.seed = rng.next();
    ceiling.base = 0.62f;
    ceiling.noise_amp = 0.18f;
    ceiling.noise_max_wavelength_m = 0.8f;
    ceiling.noise_min_wavelength_m = 0.002f;
    ceiling.rect_cell_m = 0.6f;
    ceiling.rect_density = 0.7f;
    ceiling.rect_small_cell_m = 0.2f;
    ceiling.rect_small_density = 0.1f;
    ceiling.blob_cell_m = 0.4f;
    ceiling.blob_density = 0.15f;
    scene.setWallMaterial(5, scene.addMaterial(ceiling));
  }

  auto object_material = [&](bool text) {
    TextureParams p;
    p.seed = rng.next();
    p.base = rng.uniform(0.25f, 0.75f);
    p.noise_amp = rng.uniform(0.15f, 0.28f);
    p.noise_max_wavelength_m = rng.uniform(0.3f, 0.6f);
    p.noise_min_wavelength_m = 0.0015f;
    p.noise_persistence = rng.uniform(0.7f, 0.85f);
    p.rect_small_cell_m = rng.uniform(0.08f, 0.2f);
    p.rect_density = rng.uniform(0.4f, 0.7f);
    p.rect_small_density = rng.uniform(0.2f, 0.45f);
    p.blob_cell_m = rng.uniform(0.06f, 0.15f);
    p.blob_density = rng.uniform(0.2f, 0.45f);
    if (text) {
      p.text_block_m = rng.uniform(0.003f, 0.006f);
      p.text_line_cell_m = rng.uniform(0.2f, 0.35f);
      p.text_density = 0.6f;
    }
    return scene.addMaterial(p);
  };

  const Eigen::Vector3d lo = room.min;
  const Eigen::Vector3d hi = room.max;
  constexpr int kTries = 300;
  for (int k = 0; k < config.num_boxes; ++k) {
    const bool on_wall = (k % 3 == 2);  // a third are cabinets / shelves fixed to a wall
    for (int attempt = 0; attempt < kTries; ++attempt) {
      BoxObject box;
      box.half_size = Eigen::Vector3f(rng.uniform(0.1f, 0.6f), rng.uniform(0.1f, 0.6f), rng.uniform(0.12f, 0.8f));
      Eigen::Vector3d c;
      if (on_wall) {
        box.half_size.y() = rng.uniform(0.08f, 0.25f);
        const int wall = static_cast<int>(rng.next() % 4u);
        const double along = rng.uniform(0.0f, 1.0f);
        const double z = rng.uniform(0.5f, static_cast<float>(hi.z() - lo.z()) - 0.6f) + lo.z();
        const double depth = box.half_size.y();
        // Local y points out of the wall.
        if (wall < 2) {
          box.yaw = std::numbers::pi_v<float> / 2.0f;
          c = Eigen::Vector3d(wall == 0 ? lo.x() + depth : hi.x() - depth,
                              lo.y() + 0.5 + along * (hi.y() - lo.y() - 1.0), z);
        } else {
          box.yaw = 0.0f;
          c = Eigen::Vector3d(lo.x() + 0.5 + along * (hi.x() - lo.x() - 1.0),
                              wall == 2 ? lo.y() + depth : hi.y() - depth, z);
        }
      } else {
        box.yaw = rng.uniform(-0.8f, 0.8f);
        const double r = box.half_size.head<2>().norm();
        c = Eigen::Vector3d(rng.uniform(static_cast<float>(lo.x() + r), static_cast<float>(hi.x() - r)),
                            rng.uniform(static_cast<float>(lo.y() + r), static_cast<float>(hi.y() - r)),
                            lo.z() + box.half_size.z());
      }
      const double r = box.half_size.head<2>().norm();
      if (!clearOf(keep_out, c, r, box.half_size.z(), config.keep_out_m)) continue;
      box.center = c.cast<float>();
      box.material = object_material(k % 2 == 0);
      scene.addBox(box);
      break;
    }
  }
  for (int k = 0; k < config.num_cylinders; ++k) {
    const bool pillar = (k % 3 == 0);
    for (int attempt = 0; attempt < kTries; ++attempt) {
      CylinderObject cyl;
      cyl.radius = pillar ? rng.uniform(0.08f, 0.2f) : rng.uniform(0.12f, 0.35f);
      cyl.z0 = static_cast<float>(lo.z());
      cyl.z1 = pillar ? static_cast<float>(hi.z()) : static_cast<float>(lo.z()) + rng.uniform(0.4f, 1.3f);
      const double r = cyl.radius;
      const Eigen::Vector3d c(rng.uniform(static_cast<float>(lo.x() + r), static_cast<float>(hi.x() - r)),
                              rng.uniform(static_cast<float>(lo.y() + r), static_cast<float>(hi.y() - r)),
                              0.5 * (cyl.z0 + cyl.z1));
      if (!clearOf(keep_out, c, r, 0.5 * (cyl.z1 - cyl.z0), config.keep_out_m)) continue;
      cyl.center_xy = c.head<2>().cast<float>();
      cyl.material = object_material(false);
      scene.addCylinder(cyl);
      break;
    }
  }

  const Eigen::Vector3d center = room.center();
  const Eigen::Vector3d half = room.halfExtent();
  scene.addLight({Eigen::Vector3f(static_cast<float>(center.x() - 0.5 * half.x()), static_cast<float>(center.y()),
                                  static_cast<float>(hi.z() - 0.3)),
                  0.4f, 3.0f});
  scene.addLight({Eigen::Vector3f(static_cast<float>(center.x() + 0.5 * half.x()), static_cast<float>(center.y()),
                                  static_cast<float>(hi.z() - 0.3)),
                  0.4f, 3.0f});
  scene.setAmbient(0.4f);
  return scene;
}

}  // namespace voca::synth
