# The Python module `voca` (api/python) against the `voca` command line, with pytest under the
# interpreter the module was built for (Debian's: its python3-numpy, -pil and -pytest). Absent when
# the module is not built (no pybind11 or Python headers; cross builds).
if(TARGET voca_python AND VOCA_PYTHON_EXECUTABLE)
  add_test(NAME test_python
           COMMAND ${VOCA_PYTHON_EXECUTABLE} -m pytest -q -p no:cacheprovider ${CMAKE_CURRENT_SOURCE_DIR}/python
           WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  set_tests_properties(test_python PROPERTIES
    LABELS e2e SKIP_RETURN_CODE 77
    ENVIRONMENT "PYTHONPATH=$<TARGET_FILE_DIR:voca_python>;VOCA_BIN=$<TARGET_FILE:voca>;\
VOCA_SHARED_DATA=${PROJECT_SOURCE_DIR}/../shared/data")
  voca_test_timeout(test_python 600)
  # An interpreter that is not built with ASan loads the module only with the runtime preloaded;
  # leak checks stay off, since the interpreter keeps its own objects until exit by design.
  if(VOCA_SANITIZE STREQUAL "address")
    if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
      set(asan_runtime_name libclang_rt.asan-${CMAKE_SYSTEM_PROCESSOR}.so)
    else()
      set(asan_runtime_name libasan.so)
    endif()
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=${asan_runtime_name}
                    OUTPUT_VARIABLE asan_runtime OUTPUT_STRIP_TRAILING_WHITESPACE)
    set_property(TEST test_python APPEND PROPERTY ENVIRONMENT "LD_PRELOAD=${asan_runtime}"
                                                             "ASAN_OPTIONS=detect_leaks=0")
  endif()
endif()
