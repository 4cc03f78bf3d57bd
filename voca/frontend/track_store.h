#pragma once
// What the frontend keeps of one camera from frame to frame: the pyramids of its last two images and
// its live tracks, each with an id, a position and its patch templates in a pool of fixed slots.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "voca/core/image.h"
#include "voca/frontend/patch.h"
#include "voca/frontend/pyramid.h"

namespace voca {

// Free slots of a TemplateSlots pool, the last freed handed out first. A camera's tracks hold one,
// and so does each share of a temporal step: it takes its scratch slots from the camera's before the
// shares may run on threads of their own, and gives back as many once they have finished.
class FreeSlots {
 public:
  void reserve(std::size_t capacity) { free_.reserve(capacity); }
  // Exactly the slots 0 .. count-1 are free, handed out in that order.
  void resetTo(int count);
  void clear() { free_.clear(); }
  int acquire() {
    const int slot = free_.back();
    free_.pop_back();
    return slot;
  }
  void release(int slot) { free_.push_back(slot); }
  void takeFrom(FreeSlots& from, int count) {
    for (int k = 0; k < count; ++k) release(from.acquire());
  }
  // Hands every slot held here to `to`, in the order they were freed here.
  void giveAllTo(FreeSlots& to);

 private:
  std::vector<int> free_;
};

// Each track's patch templates on every pyramid level, in slots allocated once. A slot's levels are
// built from the finest up: a round-trip check builds only the levels it runs on, and the coarser
// ones are built when a track first needs them, so a motion-vector guess that runs on the finest
// levels only (prior_pyramid_levels) never pays for them.
class TemplateSlots {
 public:
  TemplateSlots() = default;
  TemplateSlots(int slot_count, int num_levels);

  int slotCount() const { return static_cast<int>(built_levels_.size()); }
  // The levels built so far (to prefetch them).
  std::span<const PatchTemplate> built(int slot) const {
    return {templates_.data() + offset(slot), static_cast<std::size_t>(built_levels_[static_cast<std::size_t>(slot)])};
  }
  // Every level, at px in pyramid: a new track's templates.
  void buildAll(int slot, const ImagePyramid& pyramid, const Eigen::Vector2f& px, const PatchPattern& pattern) {
    buildPyramidPatch(pyramid, px, pattern, all(slot));
    built_levels_[static_cast<std::size_t>(slot)] = num_levels_;
  }
  // The finest `levels`, at px in pyramid, the coarser ones left to be built on demand: what a
  // round-trip check tracks back with, and the next frame's forward templates of a point it keeps.
  std::span<const PatchTemplate> buildFinest(int slot, const ImagePyramid& pyramid, const Eigen::Vector2f& px,
                                             const PatchPattern& pattern, int levels) {
    const std::span<PatchTemplate> templates = all(slot).first(static_cast<std::size_t>(levels));
    buildPyramidPatch(pyramid, px, pattern, templates);
    built_levels_[static_cast<std::size_t>(slot)] = levels;
    return templates;
  }
  // The finest `levels`, those not built yet built first at px in pyramid, which must be where the
  // slot's other levels were built: the track's position in its current image.
  std::span<const PatchTemplate> ensureBuilt(int slot, const ImagePyramid& pyramid, const Eigen::Vector2f& px,
                                             int levels, const PatchPattern& pattern) {
    int& built = built_levels_[static_cast<std::size_t>(slot)];
    const std::span<PatchTemplate> templates = all(slot).first(static_cast<std::size_t>(levels));
    if (built < levels) {
      buildPyramidPatch(pyramid, px, pattern, templates, static_cast<std::size_t>(built));
      built = levels;
    }
    return templates;
  }

 private:
  std::ptrdiff_t offset(int slot) const { return static_cast<std::ptrdiff_t>(slot) * num_levels_; }
  std::span<PatchTemplate> all(int slot) {
    return {templates_.data() + offset(slot), static_cast<std::size_t>(num_levels_)};
  }

  int num_levels_ = 0;
  std::vector<PatchTemplate> templates_;  // num_levels_ per slot
  std::vector<int> built_levels_;         // per slot, how many levels from level 0 are built
};

// One camera's state between frames: its last two images' pyramids and its live tracks, in parallel
// lists, oldest first. Ids are issued in increasing order and every step keeps the order, so two
// cameras' lists pair up in one merge pass.
struct CameraTracks {
  std::array<ImagePyramid, 2> pyramids;
  int current = 0;
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector2f> points;  // in the current image
  // Each track's templates in the current image. The backward track of a temporal round trip builds
  // exactly those the next frame's forward track needs, so a kept point takes over its backward
  // slot instead of rebuilding. A slot below zero: no templates (a point being decided).
  std::vector<int> slots;
  TemplateSlots templates;
  FreeSlots free_slots;

  CameraTracks() = default;
  // extra_slots: scratch slots beyond one per point, lent to the temporal step's shares.
  CameraTracks(int max_points, int extra_slots, int max_width, int max_height, int num_levels, bool can_presmooth);

  const ImagePyramid& cur() const { return pyramids[static_cast<std::size_t>(current)]; }
  const ImagePyramid& prev() const { return pyramids[static_cast<std::size_t>(1 - current)]; }
  // The new image's pyramid becomes cur(), the last one prev().
  void advance(GrayView image, bool presmooth);

  std::size_t size() const { return ids.size(); }
  void append(std::uint64_t id, const Eigen::Vector2f& px, int slot) {
    ids.push_back(id);
    points.push_back(px);
    slots.push_back(slot);
  }
  // A point detected in cur(), with the templates of every level in a fresh slot; returns the slot.
  int addDetected(std::uint64_t id, const Eigen::Vector2f& px, const PatchPattern& pattern) {
    const int slot = free_slots.acquire();
    templates.buildAll(slot, cur(), px, pattern);
    append(id, px, slot);
    return slot;
  }
  // Keeps, in order, the tracks for which keep(index, kept_so_far) is true and frees the others'
  // slots. keep may read the tracks already kept: they sit at [0, kept_so_far).
  template <class Keep>
  void retain(Keep keep) {
    std::size_t out = 0;
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (!keep(i, out)) {
        if (slots[i] >= 0) free_slots.release(slots[i]);
        continue;
      }
      ids[out] = ids[i];
      points[out] = points[i];
      slots[out] = slots[i];
      ++out;
    }
    ids.resize(out);
    points.resize(out);
    slots.resize(out);
  }
  // Forgets every track; every slot is free again.
  void clear();
};

}  // namespace voca
