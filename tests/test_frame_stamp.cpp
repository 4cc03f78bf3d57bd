// The per-frame sensor stamp inside H.264 access units: exact round trip (including values whose
// bytes need emulation prevention), placement before the first slice, and no false positives.

#include <algorithm>
#include <vector>

#include "drivers/network/frame_stamp.h"
#include "tests/test_support.h"

using namespace voca::network;

namespace {

// A made-up access unit: SPS, PPS and an IDR slice with Annex B start codes (payloads arbitrary).
const std::vector<std::uint8_t> kAccessUnit = {0, 0, 0, 1,    0x67, 0x42, 0x00, 0x1e, 0xab,   // SPS
                                               0, 0, 0, 1,    0x68, 0xce, 0x38, 0x80,         // PPS
                                               0, 0, 1, 0x65, 0x88, 0x84, 0x00, 0x21, 0xff};  // IDR slice

}  // namespace

TEST_CASE("a stamp survives the round trip exactly, emulation prevention included") {
  std::vector<std::uint8_t> stamped;
  // Zero bytes in a row (0x...000001..., 0x...000003...) must be escaped inside the NAL unit.
  for (const FrameStamp stamp : {FrameStamp{1403715273262142976, 0}, FrameStamp{0x0000000100000003, 0x0000000000000001},
                                 FrameStamp{-5, 123456789}, FrameStamp{0, 0}}) {
    stampAccessUnit(kAccessUnit, stamp, stamped);
    const auto read = readStamp(stamped);
    REQUIRE(read);
    CHECK(read->t_ns == stamp.t_ns);
    CHECK(read->frame_index == stamp.frame_index);
    // No start code can appear inside the inserted NAL unit: exactly four start codes in total.
    int start_codes = 0;
    for (std::size_t i = 0; i + 2 < stamped.size(); ++i) {
      start_codes += stamped[i] == 0 && stamped[i + 1] == 0 && stamped[i + 2] == 1;
    }
    CHECK(start_codes == 4);
  }
}

TEST_CASE("the stamp goes after the parameter sets and before the first slice, the rest unchanged") {
  std::vector<std::uint8_t> stamped;
  stampAccessUnit(kAccessUnit, {42, 7}, stamped);
  // SPS + PPS (17 bytes) untouched at the front, then the SEI NAL with a 4-byte start code.
  REQUIRE(stamped.size() > kAccessUnit.size());
  CHECK(std::equal(kAccessUnit.begin(), kAccessUnit.begin() + 17, stamped.begin()));
  CHECK(std::vector<std::uint8_t>(stamped.begin() + 17, stamped.begin() + 22) ==
        std::vector<std::uint8_t>{0, 0, 0, 1, 0x06});
  // The slice (with its 3-byte start code) is the tail, unchanged.
  CHECK(std::equal(kAccessUnit.begin() + 17, kAccessUnit.end(), stamped.end() - (kAccessUnit.size() - 17)));
  CHECK(stamped.back() == 0xff);
}

TEST_CASE("access units without our stamp have none") {
  CHECK_FALSE(readStamp(kAccessUnit));
  CHECK_FALSE(readStamp(std::vector<std::uint8_t>{}));
  // Another encoder's user-data SEI (different UUID) is not ours.
  std::vector<std::uint8_t> other = {0, 0, 0, 1, 0x06, 5, 32};
  for (int i = 0; i < 32; ++i) other.push_back(static_cast<std::uint8_t>(0x10 + i));
  other.push_back(0x80);
  other.insert(other.end(), kAccessUnit.begin() + 17, kAccessUnit.end());
  CHECK_FALSE(readStamp(other));
  // A stamp behind the first slice belongs to no header of this picture: not read.
  std::vector<std::uint8_t> behind(kAccessUnit);
  std::vector<std::uint8_t> stamp_only;
  stampAccessUnit(std::vector<std::uint8_t>{}, {1, 1}, stamp_only);
  behind.insert(behind.end(), stamp_only.begin(), stamp_only.end());
  CHECK_FALSE(readStamp(behind));
  // A P-frame without parameter sets: the stamp goes first and is found.
  std::vector<std::uint8_t> p_frame;
  stampAccessUnit(std::vector<std::uint8_t>{0, 0, 1, 0x41, 0x9a, 0x02}, {9, 3}, p_frame);
  CHECK(p_frame[4] == 0x06);
  REQUIRE(readStamp(p_frame));
  CHECK(readStamp(p_frame)->frame_index == 3);
}
