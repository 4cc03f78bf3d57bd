# noemu: dense double-precision solves run ~50x slower under qemu-user (185 s of CPU without
# finishing, against 3.7 s natively); the native run keeps them.
voca_add_test(test_backend SOURCES test_backend.cpp LIBS voca_backend voca_synth voca_eval LABELS noemu TIMEOUT 120)
voca_add_test(test_backend_config SOURCES test_backend_config.cpp LIBS voca_config LABELS asan)
target_compile_definitions(test_backend_config PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
voca_add_test(test_backend_alloc SOURCES test_backend_alloc.cpp LIBS voca_backend voca_synth LABELS noemu)
voca_add_test(test_backend_e2e SOURCES test_backend_e2e.cpp LIBS voca_eval voca_trajectory LABELS e2e TIMEOUT 900)
add_dependencies(test_backend_e2e voca)
