voca_add_test(test_config SOURCES test_config.cpp LIBS voca_config LABELS asan)
target_compile_definitions(test_config PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
