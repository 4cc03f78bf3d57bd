voca_add_test(test_config SOURCES test_config.cpp LIBS voca_formats_config LABELS asan)
target_compile_definitions(test_config PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
# The shared key-table reader behind every config section.
voca_add_test(test_config_section SOURCES test_config_section.cpp LIBS voca_formats_config LABELS asan)
