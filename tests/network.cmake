# Compress-then-analyze on loopback: the frame stamp (unit); `voca stream` -> UDP -> the network
# source and `voca run udp://...`, lossless and through a relay that drops datagrams (e2e, real time).
voca_add_test(test_frame_stamp SOURCES test_frame_stamp.cpp LIBS voca_drivers_network)
voca_add_test(test_stream_e2e SOURCES test_stream_e2e.cpp
              LIBS voca_pipeline_stream voca_pipeline_vo voca_drivers_source voca_drivers_network voca_formats_dataset
              voca_formats_calib nlohmann_json::nlohmann_json PkgConfig::FFMPEG LABELS e2e TIMEOUT 180
              THREAD_CASES "*lost datagrams*,*over TCP*,*stopped while waiting*")
add_dependencies(test_stream_e2e voca)
