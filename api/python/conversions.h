// Values between the library and Python (TUM rows, pose arrays, summaries as dicts) and voca.Error:
// what each part of the module converts the same way.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "voca_rt/voca_rt.h"

namespace voca_python {

namespace py = pybind11;

using OptionalPath = std::optional<std::filesystem::path>;
using TumValues = std::array<double, 8>;

// Adds voca.Error to the module and turns every voca_rt::Error reaching Python into one.
void addErrorType(py::module_& module);

// A voca.Error instance carrying the library's message unchanged, and what failed ("input":
// unusable input, the CLI's exit code 1; "runtime": a device, codec or the OS).
py::object makeError(const std::string& message, const char* kind);
[[noreturn]] void raise(const py::object& error);
[[noreturn]] void raiseInputError(const std::string& message);

std::string pathText(const OptionalPath& path);

// The name of a Python value's type, for TypeError messages: "float", "str".
std::string typeName(const py::handle& value);

// The eight numbers of the TUM row `voca run --out` writes for the pose, bit for bit.
TumValues tumValues(const voca_rt::Pose& pose);
py::array_t<double> tumArray(const std::vector<TumValues>& rows);

template <std::size_t N>
py::array_t<double> vectorArray(const std::array<double, N>& values) {
  py::array_t<double> array(static_cast<py::ssize_t>(N));
  std::copy(values.begin(), values.end(), array.mutable_data());
  return array;
}

const char* stateName(voca_rt::TrackingState state);
py::dict latencyDict(const voca_rt::StageLatency& latency);
py::object optionalNumber(const std::optional<double>& value);
py::dict summaryDict(const voca_rt::Summary& summary);

}  // namespace voca_python
