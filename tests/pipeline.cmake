# The staged runner with stand-in stages: ordering, drops, failures, stop requests, latency, trace.
voca_add_test(test_pipeline_runtime SOURCES test_pipeline_runtime.cpp LIBS voca_pipeline_runtime TIMEOUT 120
              THREADS)
# The VO through the pipeline on rendered, micro EuRoC and KITTI data: determinism across thread
# layouts, damaged packets, failing sources, signals to a running `voca run`, live-rate replay.
voca_add_test(test_pipeline_e2e SOURCES test_pipeline_e2e.cpp
              LIBS voca_pipeline_vo voca_drivers_source voca_drivers_encode_dataset voca_formats_dataset voca_formats_calib
                   voca_formats_trajectory LABELS e2e TIMEOUT 900
              THREAD_CASES "*byte for byte*,*--frontend-threads*,*SIGINT*,*damaged packet*,*source that fails*,*live-rate replay paces*")
add_dependencies(test_pipeline_e2e voca)
# Interposes malloc (own executable): the pipeline allocates nothing per frame beyond what FFmpeg's
# demuxer and decoder allocate, which the test counts exactly. Not in the sanitizer builds, whose
# runtimes own malloc themselves (the operator-new counting tests do run there).
if(NOT VOCA_SANITIZE)
  voca_add_test(test_pipeline_alloc SOURCES test_pipeline_alloc.cpp
                LIBS voca_pipeline_vo voca_drivers_source voca_drivers_encode voca_formats_calib TIMEOUT 300)
endif()
# The decode stage in the live runner (4 slots) with a real decoder that returns no picture for
# many packets (stream joined after its keyframe, lost packets): every slot comes back, no hang.
voca_add_test(test_decode_stage SOURCES test_decode_stage.cpp
              LIBS voca_pipeline_stages voca_drivers_encode LABELS asan TIMEOUT 120 THREADS)
# The visualisations (track overlay, motion-vector plot) on known inputs.
voca_add_test(test_overlay SOURCES test_overlay.cpp LIBS voca_pipeline_sinks LABELS asan)
# The statistics sink's guess-distance histogram on known samples.
voca_add_test(test_statistics SOURCES test_statistics.cpp LIBS voca_pipeline_sinks)
# `voca bench soak` at CI's size through the binary (issue 61): the live pipeline on a looping source
# with drops and damaged packets allocates nothing per frame, holds its RSS and accounts for every
# frame; bad options are refused. Not in the sanitizer builds: their allocators keep freed memory
# (ASan's quarantine), so RSS there says nothing about ours.
if(NOT VOCA_SANITIZE)
  voca_add_test(test_bench_soak_e2e SOURCES test_bench_soak_e2e.cpp LIBS nlohmann_json::nlohmann_json LABELS e2e
                TIMEOUT 300)
  add_dependencies(test_bench_soak_e2e voca)
endif()
