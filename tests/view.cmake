# The live view (--view): the Foxglove messages and telemetry, the server without a run, then the
# protocol and the built-in page end to end through the `voca` binary (Debian's python3 with
# python3-websockets, python3-jsonschema, python3-pil and chromium; missing ones skip, and fail in CI).
voca_add_test(test_foxglove SOURCES test_foxglove.cpp LIBS voca_pipeline_sinks nlohmann_json::nlohmann_json
              LABELS asan)
# Counts operator new (own executable, since it replaces the global allocator).
voca_add_test(test_foxglove_alloc SOURCES test_foxglove_alloc.cpp LIBS voca_pipeline_sinks)
voca_add_test(test_view_server SOURCES test_view_server.cpp LIBS voca_drivers_view LABELS asan TIMEOUT 60 THREADS)
# The view through the runner's own options on a rendered raw sequence (renders with the `voca` binary).
voca_add_test(test_view_run SOURCES test_view_run.cpp LIBS voca_pipeline_vo LABELS e2e TIMEOUT 600 THREADS)
add_dependencies(test_view_run voca)

find_program(VOCA_SYSTEM_PYTHON3 python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT VOCA_SYSTEM_PYTHON3)
  set(VOCA_SYSTEM_PYTHON3 python3)
endif()
# One rendered sequence for both, made by the first that needs it.
set(view_test_cache ${CMAKE_CURRENT_BINARY_DIR}/view-test-data)
add_test(NAME test_view COMMAND ${VOCA_SYSTEM_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/test_view.py $<TARGET_FILE:voca>
                                ${view_test_cache})
add_test(NAME test_view_page COMMAND ${VOCA_SYSTEM_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/test_view_page.py
                                     $<TARGET_FILE:voca> ${view_test_cache})
set_tests_properties(test_view test_view_page PROPERTIES LABELS e2e SKIP_RETURN_CODE 77)
voca_test_timeout(test_view 600)
if(VOCA_SANITIZE)
  # Five to seven times slower: at the recording's rate the frontend would fall behind and drop frames.
  set_tests_properties(test_view PROPERTIES ENVIRONMENT "VOCA_TEST_REPLAY_SPEED=0.2;VOCA_TEST_SANITIZER=${VOCA_SANITIZE}")
endif()
voca_test_timeout(test_view_page 600)
