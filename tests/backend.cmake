voca_add_test(test_backend SOURCES test_backend.cpp LIBS voca_backend voca_synth voca_eval TIMEOUT 120)
voca_add_test(test_backend_config SOURCES test_backend_config.cpp LIBS voca_config LABELS asan)
target_compile_definitions(test_backend_config PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
voca_add_test(test_backend_alloc SOURCES test_backend_alloc.cpp LIBS voca_backend voca_synth)
