# Runs `voca synth`, `voca encode` and `voca mv` and inspects the pictures.
voca_add_test(test_mv_cli SOURCES test_mv_cli.cpp LIBS voca_drivers_decode voca_drivers_encode voca_formats_image LABELS e2e TIMEOUT 300)
add_dependencies(test_mv_cli voca)
