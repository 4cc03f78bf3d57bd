# The small shared helpers: quantiles (voca/core), the thread CPU clock (platform/realtime) and
# forked copies (platform/process), output paths against inputs (platform/filesystem).
voca_add_test(test_core SOURCES test_core.cpp LIBS voca_core voca_platform_realtime voca_platform_process
                                              voca_platform_filesystem)
# Drawing primitives of the visualisations (voca/image/draw).
voca_add_test(test_draw SOURCES test_draw.cpp LIBS voca_image)
# The counting operator new/delete of the allocation tests and `voca bench soak` (platform/memory).
voca_add_test(test_operator_new_count SOURCES test_operator_new_count.cpp LIBS voca_platform_memory LABELS asan)
