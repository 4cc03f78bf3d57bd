// voca.run: a recorded input or a stream run through the pipeline, the poses returned as TUM rows.
#pragma once

#include <pybind11/pybind11.h>

namespace voca_python {

void bindRun(pybind11::module_& module);

}  // namespace voca_python
