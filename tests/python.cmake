# The Python module `voca` (api/python) against the `voca` command line, with pytest under the
# interpreter the module was built for (Debian's: its python3-numpy, -pil and -pytest). Absent when
# the module is not built (no pybind11 or Python headers; cross builds).
if(TARGET voca_python AND VOCA_PYTHON_EXECUTABLE)
  add_test(NAME test_python
           COMMAND ${VOCA_PYTHON_EXECUTABLE} -m pytest -q -p no:cacheprovider ${CMAKE_CURRENT_SOURCE_DIR}/python
           WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  set_tests_properties(test_python PROPERTIES
    LABELS e2e TIMEOUT 600 SKIP_RETURN_CODE 77
    ENVIRONMENT "PYTHONPATH=$<TARGET_FILE_DIR:voca_python>;VOCA_BIN=$<TARGET_FILE:voca>;\
VOCA_SHARED_DATA=${PROJECT_SOURCE_DIR}/../shared/data")
endif()
