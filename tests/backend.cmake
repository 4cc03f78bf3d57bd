# Dense double-precision solves run ~50x slower under qemu-user (the whole file took over 185 s of
# CPU there, against 3.7 s natively), so the emulated cross run leaves out the doctest suite "long"
# (the 30 s sequences); the Jacobians and a short estimator run still run on the emulated CPU.
set(backend_test_args "")
if(CMAKE_CROSSCOMPILING)
  set(backend_test_args --test-suite-exclude=long)
endif()
voca_add_test(test_backend SOURCES test_backend.cpp LIBS voca_backend voca_synth voca_eval TIMEOUT 120
  ARGS ${backend_test_args})
voca_add_test(test_backend_config SOURCES test_backend_config.cpp LIBS voca_formats_config LABELS asan)
target_compile_definitions(test_backend_config PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
voca_add_test(test_backend_alloc SOURCES test_backend_alloc.cpp LIBS voca_backend voca_synth TIMEOUT 240)
voca_add_test(test_backend_e2e SOURCES test_backend_e2e.cpp LIBS voca_pipeline_vo voca_eval voca_formats_trajectory LABELS e2e
              TIMEOUT 900)
add_dependencies(test_backend_e2e voca)
voca_add_test(test_backend_bench SOURCES test_backend_bench.cpp LIBS voca_pipeline_bench voca_synth)
