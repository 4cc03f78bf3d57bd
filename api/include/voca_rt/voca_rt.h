#pragma once
// VOCA-RT's public API: causal stereo visual odometry on H.264 video with the codec's motion vectors
// as tracking priors. Link VocaRT::voca_rt (CMake) or voca-rt (pkg-config).

#include "voca_rt/calibration.h"
#include "voca_rt/error.h"
#include "voca_rt/evaluate.h"
#include "voca_rt/odometry.h"
#include "voca_rt/run.h"
#include "voca_rt/version.h"
#include "voca_rt/video_folder.h"
