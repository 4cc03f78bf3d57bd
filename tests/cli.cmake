# The `voca` commands through the binary with their output checked (odd frame sizes end to end,
# eval, track, bench, demo). Needs the voca tool built first.
voca_add_test(test_cli_e2e SOURCES test_cli_e2e.cpp
              LIBS voca_formats_dataset voca_drivers_decode voca_formats_calib voca_formats_image voca_formats_trajectory
                   nlohmann_json::nlohmann_json LABELS e2e TIMEOUT 600)
add_dependencies(test_cli_e2e voca)
