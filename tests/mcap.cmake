# MCAP recordings (drivers/mcap): the writer against the specification's byte layout and on failing
# files (asan: unwritable paths, /dev/full, a file size limit); its steady-state writes without
# allocation (own executable: it replaces operator new); and the files it writes read back by the
# independent Python reader (tests/mcap_reader.py), also cut, killed and stopped by a full file.
voca_add_test(test_mcap SOURCES test_mcap.cpp LIBS voca_drivers_mcap LABELS asan)
voca_add_test(test_mcap_alloc SOURCES test_mcap_alloc.cpp LIBS voca_drivers_mcap)

add_executable(mcap_sample_writer mcap_sample_writer.cpp)
target_link_libraries(mcap_sample_writer PRIVATE voca_drivers_mcap nlohmann_json::nlohmann_json fmt::fmt)
voca_target_defaults(mcap_sample_writer)
# Debian's interpreter: the reader needs only the standard library, but a python3 earlier on PATH
# (pyenv, a virtualenv) may be another version than the one tools/setup.sh provides.
find_program(VOCA_SYSTEM_PYTHON3 python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT VOCA_SYSTEM_PYTHON3)
  set(VOCA_SYSTEM_PYTHON3 python3)
endif()
# A target of the test's name builds what it runs, as for the doctest executables (tools/test.sh
# builds a test by its name).
add_custom_target(test_mcap_reader DEPENDS mcap_sample_writer)
add_test(NAME test_mcap_reader
         COMMAND ${VOCA_SYSTEM_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/test_mcap_reader.py
                 --writer $<TARGET_FILE:mcap_sample_writer>)
# Runs a host executable from Python: kept out of the emulated cross run.
set_tests_properties(test_mcap_reader PROPERTIES LABELS "unit;noemu")
voca_test_timeout(test_mcap_reader 300)
# `voca run --mcap` end to end through the same reader: every pose recorded, SIGINT, /dev/full.
add_test(NAME test_mcap_run
         COMMAND ${VOCA_SYSTEM_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/test_mcap_run.py --voca $<TARGET_FILE:voca>
                 --data ${PROJECT_SOURCE_DIR}/../shared/data)
# Labelled threads: the run's MCAP writer thread beside the pipeline's.
set_tests_properties(test_mcap_run PROPERTIES LABELS "e2e;threads" SKIP_RETURN_CODE 77)
voca_test_timeout(test_mcap_run 300)
