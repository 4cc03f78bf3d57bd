# V4L2 capture against an in-process fake device that speaks the kernel protocol: discovery, every
# pixel format, side-by-side split, stereo pairing, controls, a device vanishing mid-stream.
add_library(voca_test_fake_v4l2 STATIC fake_v4l2.cpp)
target_link_libraries(voca_test_fake_v4l2 PUBLIC voca_platform_v4l2 voca_drivers_capture voca_platform_realtime)
target_include_directories(voca_test_fake_v4l2 PUBLIC ${PROJECT_SOURCE_DIR})
voca_target_defaults(voca_test_fake_v4l2)
voca_add_test(test_capture SOURCES test_capture.cpp LIBS voca_test_fake_v4l2 voca_drivers_capture fmt::fmt
              LABELS asan)
# Counts operator new (own executable): capture allocates nothing per frame once streaming.
voca_add_test(test_capture_alloc SOURCES test_capture_alloc.cpp LIBS voca_test_fake_v4l2 voca_drivers_capture)
# Live cameras (paced fake) through the staged VO pipeline with the live policy.
voca_add_test(test_capture_pipeline SOURCES test_capture_pipeline.cpp
              LIBS voca_test_fake_v4l2 voca_pipeline_vo voca_formats_calib voca_platform_filesystem TIMEOUT 120
              THREADS)
# `voca record`'s path from the fake cameras to a video folder that `voca run`'s runner reads back.
voca_add_test(test_capture_record SOURCES test_capture_record.cpp
              LIBS voca_test_fake_v4l2 voca_pipeline_vo voca_drivers_source voca_formats_dataset voca_drivers_decode
              voca_formats_calib voca_platform_filesystem TIMEOUT 120 THREADS)
# libcamera without a camera: the manager starts, lists cameras, names missing ones.
if(VOCA_WITH_LIBCAMERA)
  voca_add_test(test_capture_libcamera SOURCES test_capture_libcamera.cpp LIBS voca_drivers_capture)
endif()
