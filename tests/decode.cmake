voca_add_test(test_decode SOURCES test_decode.cpp LIBS voca_drivers_decode voca_drivers_encode)
voca_add_test(test_decode_bad SOURCES test_decode_bad.cpp LIBS voca_drivers_decode voca_drivers_encode
              voca_formats_dataset LABELS asan)
voca_add_test(test_decode_e2e SOURCES test_decode_e2e.cpp LIBS voca_drivers_decode voca_drivers_encode
              voca_formats_dataset voca_formats_image LABELS e2e TIMEOUT 300)
# Counting operator new: the per-frame decode path allocates nothing after warm-up (own executable,
# since it replaces the global allocator).
voca_add_test(test_decode_alloc SOURCES test_decode_alloc.cpp LIBS voca_drivers_decode voca_drivers_encode)
# Stream structures the method cannot use (B-frames, several references, interlacing, other
# formats) are refused by name; tiny clips made in the test with libavcodec.
voca_add_test(test_decode_structure SOURCES test_decode_structure.cpp LIBS voca_drivers_decode PkgConfig::FFMPEG
              LABELS asan)
# Hardware pixels + software vectors paired by pts, with a stand-in pixel decoder that reorders and
# drops; the V4L2 M2M probe's capability rule.
voca_add_test(test_decode_pairing SOURCES test_decode_pairing.cpp LIBS voca_drivers_decode voca_drivers_encode
              voca_platform_v4l2 PkgConfig::FFMPEG)
# `voca bench decode` on a VOCA folder made in the test: rates and bitrates as stream and recording.
voca_add_test(test_decode_bench SOURCES test_decode_bench.cpp LIBS voca_pipeline_bench voca_drivers_encode)
# Software decoding allocates its picture memory at the first picture: a randomly damaged stream
# never makes the decoder allocate another picture later (resident memory flat in a soak).
voca_add_test(test_decode_picture_pool SOURCES test_decode_picture_pool.cpp LIBS voca_drivers_decode
              voca_drivers_encode PkgConfig::FFMPEG)
