# Dataset folders: layouts, frame pairing, errors for malformed folders, and the EuRoC writer.
voca_add_test(test_dataset SOURCES test_dataset.cpp LIBS voca_formats_dataset voca_formats_image fmt::fmt LABELS asan)
# The same readers on the real EuRoC and KITTI excerpts in ../shared/data.
voca_add_test(test_dataset_data SOURCES test_dataset_data.cpp LIBS voca_formats_dataset voca_formats_image LABELS e2e)
# Image datasets replayed as a stereo source: unreadable images are damaged frames, or errors when strict.
voca_add_test(test_dataset_source SOURCES test_dataset_source.cpp
              LIBS voca_drivers_source voca_formats_dataset voca_formats_image LABELS asan)
# A video folder looped as one long lossy stream (`voca bench soak`): times, pts, drops that resume at
# keyframes, damaged packets, no allocation per frame (own executable: it counts operator new).
voca_add_test(test_looping_source SOURCES test_looping_source.cpp
              LIBS voca_drivers_source voca_drivers_encode voca_formats_dataset)
