# The shared progress line (platform/terminal): terminal and log behaviour on a temporary file.
voca_add_test(test_progress_line SOURCES test_progress_line.cpp LIBS voca_platform_terminal)
