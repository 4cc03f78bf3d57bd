# The live view (--view): the Foxglove messages and telemetry.
voca_add_test(test_foxglove SOURCES test_foxglove.cpp LIBS voca_pipeline_sinks nlohmann_json::nlohmann_json
              LABELS asan)
# Counts operator new (own executable, since it replaces the global allocator).
voca_add_test(test_foxglove_alloc SOURCES test_foxglove_alloc.cpp LIBS voca_pipeline_sinks)
