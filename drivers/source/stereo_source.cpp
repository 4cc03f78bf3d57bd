#include "drivers/source/stereo_source.h"

#include <stdexcept>

namespace voca {

bool StereoSource::next(RawStereoFrame& /*frame*/) {
  throw std::logic_error(info().description + ": delivers encoded packets, not raw frames");
}

bool StereoSource::next(EncodedStereoPacket& /*packet*/) {
  throw std::logic_error(info().description + ": delivers raw frames, not encoded packets");
}

}  // namespace voca
