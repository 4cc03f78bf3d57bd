# The small shared helpers: quantiles (voca/core) and the thread CPU clock (platform/realtime).
voca_add_test(test_core SOURCES test_core.cpp LIBS voca_core voca_platform_realtime)
# Drawing primitives of the visualisations (voca/image/draw).
voca_add_test(test_draw SOURCES test_draw.cpp LIBS voca_image)
