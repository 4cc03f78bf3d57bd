voca_add_test(test_frontend SOURCES test_frontend.cpp LIBS voca_frontend)
voca_add_test(test_frontend_alloc SOURCES test_frontend_alloc.cpp LIBS voca_frontend)
voca_add_test(test_frontend_config SOURCES test_frontend_config.cpp LIBS voca_config LABELS asan)
target_compile_definitions(test_frontend_config PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
