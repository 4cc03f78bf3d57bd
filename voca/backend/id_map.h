#pragma once
// A fixed-capacity hash map from track id to landmark slot (open addressing, linear probing,
// backward-shift deletion): insertions and deletions never allocate after construction.

#include <cstdint>
#include <vector>

namespace voca {

// Maps uint64 track ids to int slots; capacity fixed at construction (kept at most half full).
class IdSlotMap {
 public:
  explicit IdSlotMap(int max_entries = 0) {
    std::size_t size = 16;
    while (size < 2 * static_cast<std::size_t>(max_entries) + 1) size *= 2;
    entries_.assign(size, Entry{});
    mask_ = size - 1;
  }

  // The slot stored for id, or -1.
  int find(std::uint64_t id) const {
    for (std::size_t i = hash(id);; i = (i + 1) & mask_) {
      const Entry& e = entries_[i];
      if (e.slot < 0) return -1;
      if (e.id == id) return e.slot;
    }
  }
  // Inserts or overwrites; false when the map is full.
  bool insert(std::uint64_t id, int slot) {
    if (2 * (size_ + 1) > entries_.size()) return false;
    for (std::size_t i = hash(id);; i = (i + 1) & mask_) {
      Entry& e = entries_[i];
      if (e.slot < 0) {
        e = {id, slot};
        ++size_;
        return true;
      }
      if (e.id == id) {
        e.slot = slot;
        return true;
      }
    }
  }
  void erase(std::uint64_t id) {
    std::size_t i = hash(id);
    for (;; i = (i + 1) & mask_) {
      if (entries_[i].slot < 0) return;
      if (entries_[i].id == id) break;
    }
    // Backward shift: move later entries of the probe chain into the hole so lookups stay correct.
    std::size_t hole = i;
    for (std::size_t j = (i + 1) & mask_; entries_[j].slot >= 0; j = (j + 1) & mask_) {
      const std::size_t home = hash(entries_[j].id);
      // Entry j may move to the hole when its home is not in (hole, j] cyclically.
      const bool home_in_range = hole <= j ? (home > hole && home <= j) : (home > hole || home <= j);
      if (!home_in_range) {
        entries_[hole] = entries_[j];
        hole = j;
      }
    }
    entries_[hole] = Entry{};
    --size_;
  }
  void clear() {
    for (Entry& e : entries_) e = Entry{};
    size_ = 0;
  }
  std::size_t size() const { return size_; }

 private:
  struct Entry {
    std::uint64_t id = 0;
    int slot = -1;
  };
  std::size_t hash(std::uint64_t id) const {
    id ^= id >> 33;
    id *= 0xff51afd7ed558ccdULL;
    id ^= id >> 33;
    return static_cast<std::size_t>(id) & mask_;
  }

  std::vector<Entry> entries_;
  std::size_t mask_ = 0;
  std::size_t size_ = 0;
};

}  // namespace voca
