#include "drivers/network/frame_stamp.h"

#include <algorithm>
#include <array>
#include <cstring>

namespace voca::network {

namespace {

// "VOCA-RT stamp v1": identifies our user data among other SEI.
constexpr std::array<std::uint8_t, 16> kUuid = {'V', 'O', 'C', 'A', '-', 'R', 'T', ' ',
                                                's', 't', 'a', 'm', 'p', ' ', 'v', '1'};
constexpr std::uint8_t kSeiNal = 6;  // nal_ref_idc 0, nal_unit_type 6 (SEI)
constexpr int kUserDataUnregistered = 5;
constexpr std::size_t kPayloadSize = kUuid.size() + 16;  // uuid, t_ns, frame_index

bool isSlice(std::uint8_t nal_header) {
  const int type = nal_header & 0x1f;
  return type == 1 || type == 5;  // non-IDR / IDR slice
}

// Offset of the next start code 00 00 01 at or after `from`, or size.
std::size_t nextStartCode(std::span<const std::uint8_t> data, std::size_t from) {
  for (std::size_t i = from; i + 2 < data.size(); ++i) {
    if (data[i] == 0 && data[i + 1] == 0 && data[i + 2] == 1) return i;
  }
  return data.size();
}

void putBigEndian(std::uint8_t* out, std::int64_t value) {
  const auto u = static_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) out[i] = static_cast<std::uint8_t>(u >> (56 - 8 * i));
}

std::int64_t getBigEndian(const std::uint8_t* in) {
  std::uint64_t u = 0;
  for (int i = 0; i < 8; ++i) u = (u << 8) | in[i];
  return static_cast<std::int64_t>(u);
}

}  // namespace

void stampAccessUnit(std::span<const std::uint8_t> access_unit, const FrameStamp& stamp,
                     std::vector<std::uint8_t>& out) {
  // Where the first slice's start code begins (a 4-byte start code includes the zero before it).
  std::size_t insert_at = access_unit.size();
  for (std::size_t sc = nextStartCode(access_unit, 0); sc < access_unit.size();
       sc = nextStartCode(access_unit, sc + 3)) {
    if (sc + 3 < access_unit.size() && isSlice(access_unit[sc + 3])) {
      insert_at = (sc > 0 && access_unit[sc - 1] == 0) ? sc - 1 : sc;
      break;
    }
  }
  std::array<std::uint8_t, 2 + kPayloadSize> message{};
  message[0] = kUserDataUnregistered;
  message[1] = static_cast<std::uint8_t>(kPayloadSize);
  std::copy(kUuid.begin(), kUuid.end(), message.begin() + 2);
  putBigEndian(message.data() + 2 + kUuid.size(), stamp.t_ns);
  putBigEndian(message.data() + 2 + kUuid.size() + 8, stamp.frame_index);

  out.clear();
  out.insert(out.end(), access_unit.begin(), access_unit.begin() + static_cast<std::ptrdiff_t>(insert_at));
  for (std::uint8_t b : {0, 0, 0, 1, static_cast<int>(kSeiNal)}) out.push_back(b);
  // Emulation prevention: no 00 00 0x (x <= 3) inside a NAL unit's payload.
  int zeros = 0;
  for (std::uint8_t b : message) {
    if (zeros >= 2 && b <= 3) {
      out.push_back(3);
      zeros = 0;
    }
    out.push_back(b);
    zeros = b == 0 ? zeros + 1 : 0;
  }
  out.push_back(0x80);  // rbsp_trailing_bits
  out.insert(out.end(), access_unit.begin() + static_cast<std::ptrdiff_t>(insert_at), access_unit.end());
}

std::optional<FrameStamp> readStamp(std::span<const std::uint8_t> access_unit) {
  for (std::size_t sc = nextStartCode(access_unit, 0); sc < access_unit.size();) {
    const std::size_t nal = sc + 3;
    const std::size_t end = nextStartCode(access_unit, nal);
    if (nal >= access_unit.size() || isSlice(access_unit[nal])) break;
    if ((access_unit[nal] & 0x1f) == kSeiNal) {
      // Undo emulation prevention for the SEI messages (only the first bytes are needed).
      std::array<std::uint8_t, 64> rbsp{};
      std::size_t n = 0;
      int zeros = 0;
      for (std::size_t i = nal + 1; i < end && n < rbsp.size(); ++i) {
        if (zeros >= 2 && access_unit[i] == 3) {
          zeros = 0;
          continue;
        }
        rbsp[n++] = access_unit[i];
        zeros = access_unit[i] == 0 ? zeros + 1 : 0;
      }
      // Only the first message of each SEI NAL unit is looked at: ours is alone in its unit.
      if (n >= 2 + kPayloadSize && rbsp[0] == kUserDataUnregistered && rbsp[1] == kPayloadSize &&
          std::equal(kUuid.begin(), kUuid.end(), rbsp.begin() + 2)) {
        FrameStamp stamp;
        stamp.t_ns = getBigEndian(rbsp.data() + 2 + kUuid.size());
        stamp.frame_index = getBigEndian(rbsp.data() + 2 + kUuid.size() + 8);
        return stamp;
      }
    }
    sc = end;
  }
  return std::nullopt;
}

bool isIdrAccessUnit(std::span<const std::uint8_t> access_unit) {
  for (std::size_t sc = nextStartCode(access_unit, 0); sc + 3 < access_unit.size();
       sc = nextStartCode(access_unit, sc + 3)) {
    if (isSlice(access_unit[sc + 3])) return (access_unit[sc + 3] & 0x1f) == 5;
  }
  return false;
}

}  // namespace voca::network
