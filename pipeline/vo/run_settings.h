#pragma once
// How to run the pipeline as people and programs give it (numbers and names), checked and turned into
// VoRunOptions in one place for the command line and the library API alike. Errors name the option
// as the command line spells it, since that is where most users meet them.

#include <string>

#include "pipeline/vo/vo_run.h"

namespace voca::pipeline {

struct RunSettings {
  int threads = 0;                   // 0: one per stage; 1: all in one; N: grouped in order (--threads)
  int frontend_threads = 0;          // 0: automatic; 1 or 2 (--frontend-threads)
  std::string pins;                  // --pin, "decode:0,frontend:0,backend:1"
  std::string scheduling = "other";  // --sched: other, fifo, rr
  int priority = 50;                 // --priority, 1-99 for fifo and rr
  bool lock_memory = false;          // --mlock
  bool realtime = false;             // --realtime
  double speed = 1.0;                // --speed
  bool strict = false;               // --strict
  std::string decoder = "auto";      // --decoder: auto, software, vaapi, v4l2m2m
  bool skip_deblock = false;         // --skip-deblock
  std::string trace_file;            // --trace
  std::string statistics_file;       // --stats
};

// Throws InputError naming the option for a value out of range or a name it does not know.
void applyRunSettings(const RunSettings& settings, VoRunOptions& options);

}  // namespace voca::pipeline
