# The live view (--view): the Foxglove messages and telemetry, and the server without a run.
voca_add_test(test_foxglove SOURCES test_foxglove.cpp LIBS voca_pipeline_sinks nlohmann_json::nlohmann_json
              LABELS asan)
# Counts operator new (own executable, since it replaces the global allocator).
voca_add_test(test_foxglove_alloc SOURCES test_foxglove_alloc.cpp LIBS voca_pipeline_sinks)
voca_add_test(test_view_server SOURCES test_view_server.cpp LIBS voca_drivers_view LABELS asan TIMEOUT 60)
