# The staged runner with stand-in stages: ordering, drops, failures, stop requests, latency, trace.
voca_add_test(test_pipeline_runtime SOURCES test_pipeline_runtime.cpp LIBS voca_pipeline_runtime TIMEOUT 120)
