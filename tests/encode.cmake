# Encoder: synthetic sequences to .mp4 and back, dataset folders to the VOCA video layout (unit),
# the micro EuRoC sequence (e2e), bad input (asan).
voca_add_test(test_encode SOURCES test_encode.cpp LIBS voca_drivers_encode PkgConfig::FFMPEG TIMEOUT 120)
voca_add_test(test_encode_dataset SOURCES test_encode_dataset.cpp
              LIBS voca_drivers_encode_dataset PkgConfig::FFMPEG TIMEOUT 120)
voca_add_test(test_encode_bad_input SOURCES test_encode_bad_input.cpp
              LIBS voca_drivers_encode_dataset voca_formats_image voca_formats_calib voca_synth PkgConfig::FFMPEG
              LABELS asan TIMEOUT 120)
voca_add_test(test_encode_e2e SOURCES test_encode_e2e.cpp
              LIBS voca_drivers_encode_dataset voca_formats_calib voca_formats_trajectory PkgConfig::FFMPEG LABELS e2e TIMEOUT 600)
# The live encoder: selection with injected probes, low-latency libx264 (one packet per frame).
voca_add_test(test_live_encoder SOURCES test_live_encoder.cpp LIBS voca_drivers_encode voca_drivers_decode
              PkgConfig::FFMPEG TIMEOUT 60)
