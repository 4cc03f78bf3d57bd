// voca.Odometry: frames pushed from Python (H.264 access units or gray NumPy images), poses polled.
#pragma once

#include <pybind11/pybind11.h>

namespace voca_python {

void bindOdometry(pybind11::module_& module);

}  // namespace voca_python
