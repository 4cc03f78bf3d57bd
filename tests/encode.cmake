# Encoder: synthetic sequences to .mp4 and back (unit), bad input (asan).
voca_add_test(test_encode SOURCES test_encode.cpp LIBS voca_drivers_encode PkgConfig::FFMPEG TIMEOUT 120)
