#pragma once
// Built-in stereo rigs for synthetic sequences (published calibrations of EuRoC and TUM-VI) and
// the bridge from a calibrated camera to the renderer's ray table.

#include <optional>
#include <string_view>

#include "voca/calib/calibration.h"
#include "voca/synth/renderer.h"

namespace voca::synth {

// EuRoC MAV cam0/cam1 (Kalibr camchain published with the dataset): pinhole-radtan 752x480,
// body frame = the IMU frame.
StereoRig eurocRig();
// TUM-VI 512x512 cam0/cam1 (Kalibr camchain published with the dataset): kb4 (equidistant),
// body frame = the IMU frame.
StereoRig tumviRig();
// "euroc" or "tumvi"; nullopt for other names.
std::optional<StereoRig> builtinRig(std::string_view name);

// Per-pixel rays of a calibrated camera through its model's unproject.
RayTable makeRayTable(const CameraCalibration& camera);

}  // namespace voca::synth
