# Calibration readers on synthetic files, including malformed ones (also run under AddressSanitizer).
voca_add_test(test_calib SOURCES test_calib.cpp LIBS voca_formats_calib voca_formats_image nlohmann_json::nlohmann_json LABELS asan)
# Every calibration file in ../shared/data, and the radtan/double-sphere cross-check of the EuRoC rig.
voca_add_test(test_calib_data SOURCES test_calib_data.cpp LIBS voca_formats_calib LABELS e2e)
# The EuRoC rig calibrated twice (radtan sensor.yaml, Basalt double sphere): same pixels, same points.
voca_add_test(test_calib_crosscheck SOURCES test_calib_crosscheck.cpp LIBS voca_formats_calib LABELS e2e)
