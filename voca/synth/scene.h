#pragma once
// The synthetic 3-D scene: a textured room (z up, floor at the room's min z) with boxes, vertical
// cylinders and marker discs inside, intersected analytically by rays and shaded by static lights.

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "voca/synth/texture.h"

namespace voca::synth {

// The room's inside: an axis-aligned box in world coordinates (metres, z up).
struct RoomBox {
  Eigen::Vector3d min = Eigen::Vector3d(-4.5, -3.5, 0.0);
  Eigen::Vector3d max = Eigen::Vector3d(4.5, 3.5, 3.0);
  Eigen::Vector3d center() const { return 0.5 * (min + max); }
  Eigen::Vector3d halfExtent() const { return 0.5 * (max - min); }
  // Distance from an inside point to the nearest wall, floor or ceiling (negative outside).
  double clearance(const Eigen::Vector3d& p) const { return std::min((p - min).minCoeff(), (max - p).minCoeff()); }
};

// A box turned by `yaw` about the vertical axis.
struct BoxObject {
  Eigen::Vector3f center;
  Eigen::Vector3f half_size;
  float yaw = 0.0f;
  int material = 0;
};

// A vertical cylinder from z0 to z1 (top cap at z1; the bottom is assumed to rest on something).
struct CylinderObject {
  Eigen::Vector2f center_xy;
  float radius = 0.1f;
  float z0 = 0.0f;
  float z1 = 1.0f;
  int material = 0;
};

// A flat, uniformly coloured disc: a marker with a known centre, used to check the geometry.
struct DiscObject {
  Eigen::Vector3f center;
  Eigen::Vector3f normal;
  float radius = 0.05f;
  float albedo = 1.0f;
};

// A static point light; shading is Lambertian and view-independent, so a surface point has the same
// brightness from every viewpoint (the brightness constancy trackers assume).
struct PointLight {
  Eigen::Vector3f position;
  float intensity = 0.5f;
  float falloff_m = 3.0f;  // distance at which the light's contribution has halved
};

// Result of a ray-scene intersection.
struct Hit {
  float t = 0.0f;  // distance along the (unit) ray
  Eigen::Vector3f point;
  Eigen::Vector3f normal;    // unit, facing the ray's origin side of the surface
  float u = 0.0f, v = 0.0f;  // surface coordinates, metres
  int surface = -1;          // distinct for every face or patch: a change between pixels is an edge
  int material = -1;         // index into the scene's textures, or -1 for a disc (uniform albedo)
  float albedo = 0.0f;       // for discs
};

// Options for the procedurally generated room.
struct SceneConfig {
  RoomBox room;
  int num_boxes = 16;
  int num_cylinders = 8;
  double keep_out_m = 0.6;  // objects stay this far from every keep-out point (the camera path)
};

// The scene: room walls + objects + lights. Built once, then only read (safe to share across threads).
class Scene {
 public:
  explicit Scene(const RoomBox& room = RoomBox());

  // A furnished room: textured walls, boxes and cylinders at various depths, and two ceiling lights.
  // Objects are placed away from keep_out points (sample the camera path there). Deterministic in seed.
  static Scene generate(const SceneConfig& config, std::span<const Eigen::Vector3d> keep_out, std::uint32_t seed);

  int addMaterial(const TextureParams& params);
  // Walls get materials 0..5 in the order -x, +x, -y, +y, floor, ceiling; set them after adding materials.
  void setWallMaterial(int wall, int material);
  void addBox(const BoxObject& box);
  void addCylinder(const CylinderObject& cylinder) { cylinders_.push_back(cylinder); }
  void addDisc(const DiscObject& disc) { discs_.push_back(disc); }
  void addLight(const PointLight& light) { lights_.push_back(light); }
  void setAmbient(float ambient) { ambient_ = ambient; }

  // Nearest hit of the ray origin + t dir (dir unit, origin inside the room). Always hits a wall
  // when the origin is inside the room.
  bool intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, Hit& hit) const;
  // Gray level (0..255 scale, not clamped) seen along a ray at a hit, the texture filtered over
  // footprint_m (the sample's extent on the surface).
  float radiance(const Hit& hit, float footprint_m) const;

  const RoomBox& room() const { return room_; }
  const std::vector<BoxObject>& boxes() const { return boxes_; }
  const std::vector<CylinderObject>& cylinders() const { return cylinders_; }

 private:
  RoomBox room_;
  Eigen::Vector3f room_min_, room_max_;
  int wall_material_[6] = {0, 0, 0, 0, 0, 0};
  std::vector<ProceduralTexture> materials_;
  std::vector<BoxObject> boxes_;
  std::vector<Eigen::Vector2f> box_cos_sin_;  // of each box's yaw, so rays need no trigonometry
  std::vector<float> box_radius2_;            // squared bounding-sphere radius, for a cheap rejection test
  std::vector<CylinderObject> cylinders_;
  std::vector<DiscObject> discs_;
  std::vector<PointLight> lights_;
  float ambient_ = 0.45f;
};

}  // namespace voca::synth
