#include "voca_rt/calibration.h"

#include "api/src/api_internal.h"
#include "formats/calib/calibration_io.h"

namespace voca_rt {

Calibration Calibration::load(const std::string& path) {
  return detail::translated([&] { return detail::calibration(voca::loadCalibration(path)); });
}

}  // namespace voca_rt
