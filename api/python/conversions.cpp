#include "conversions.h"

#include <charconv>
#include <exception>
#include <stdexcept>
#include <system_error>

namespace voca_python {
namespace {

// voca.Error, created when the module loads; lives as long as the interpreter.
PyObject* error_type = nullptr;

const char* kindName(voca_rt::Error::Kind kind) { return kind == voca_rt::Error::Kind::kInput ? "input" : "runtime"; }

}  // namespace

void addErrorType(py::module_& module) {
  error_type = PyErr_NewExceptionWithDoc(
      "voca.Error",
      "Bad input or a failed run. str(error) is the message `voca` prints after 'error: ' for the same problem "
      "(naming the file, field, option or frame). error.kind: 'input' (unusable input; the CLI exits 1) or "
      "'runtime' (a device, codec or the operating system failed). Errors of voca.run that end a run also carry "
      "error.poses (the (N, 8) TUM rows estimated before) and error.summary.",
      PyExc_RuntimeError, nullptr);
  if (error_type == nullptr) throw py::error_already_set();
  module.attr("Error") = py::handle(error_type);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const voca_rt::Error& e) {
      const py::object error = makeError(e.what(), kindName(e.kind()));
      PyErr_SetObject(error_type, error.ptr());
    }
  });
}

py::object makeError(const std::string& message, const char* kind) {
  py::object error = py::reinterpret_borrow<py::object>(error_type)(message);
  error.attr("kind") = kind;
  return error;
}

[[noreturn]] void raise(const py::object& error) {
  PyErr_SetObject(error_type, error.ptr());
  throw py::error_already_set();
}

[[noreturn]] void raiseInputError(const std::string& message) { raise(makeError(message, "input")); }

std::string pathText(const OptionalPath& path) { return path ? path->string() : std::string(); }

std::string typeName(const py::handle& value) { return py::str(py::type::handle_of(value).attr("__name__")); }

// The eight numbers of the TUM row `voca run --out` writes for the pose, read back from the very text
// voca_rt::tumRow formats: the time as its nine-decimal seconds read as a double (a nanosecond count
// of today's epoch exceeds 2^53, so t_ns / 1e9 could differ in the last bit), and the shortest exact
// forms of the pose's numbers. Equal to parsing the CLI's file, bit for bit.
TumValues tumValues(const voca_rt::Pose& pose) {
  const std::string row = voca_rt::tumRow(pose);
  TumValues values{};
  const char* at = row.data();
  const char* const end = row.data() + row.size();
  for (double& value : values) {
    while (at < end && *at == ' ') ++at;
    const std::from_chars_result read = std::from_chars(at, end, value);
    if (read.ec != std::errc()) throw std::logic_error("voca_rt::tumRow wrote a row that does not read back: " + row);
    at = read.ptr;
  }
  return values;
}

py::array_t<double> tumArray(const std::vector<TumValues>& rows) {
  py::array_t<double> array({static_cast<py::ssize_t>(rows.size()), py::ssize_t{8}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t j = 0; j < 8; ++j) out(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(j)) = rows[i][j];
  }
  return array;
}

const char* stateName(voca_rt::TrackingState state) {
  switch (state) {
    case voca_rt::TrackingState::kOk:
      return "ok";
    case voca_rt::TrackingState::kReset:
      return "reset";
    case voca_rt::TrackingState::kLost:
      return "lost";
  }
  return "lost";
}

py::dict latencyDict(const voca_rt::StageLatency& latency) {
  py::dict d;
  d["encode_ms"] = latency.encode_ms;
  d["decode_ms"] = latency.decode_ms;
  d["frontend_ms"] = latency.frontend_ms;
  d["backend_ms"] = latency.backend_ms;
  d["end_to_end_ms"] = latency.end_to_end_ms;
  return d;
}

py::object optionalNumber(const std::optional<double>& value) {
  return value ? py::object(py::float_(*value)) : py::object(py::none());
}

py::dict summaryDict(const voca_rt::Summary& s) {
  py::dict d;
  d["input"] = s.input;
  d["config"] = s.config;
  d["started"] = s.started;
  d["frames"] = s.frames;
  d["keyframes"] = s.keyframes;
  d["resets"] = s.resets;
  d["lost"] = s.lost;
  d["dropped"] = s.dropped;
  d["damaged"] = s.damaged;
  d["frames_lost"] = s.frames_lost;
  d["unpaired"] = s.unpaired;
  d["threads"] = s.threads;
  d["wall_s"] = s.wall_s;
  d["fps"] = s.frames_per_second;
  py::dict end_to_end;
  end_to_end["p50"] = s.end_to_end_ms[0];
  end_to_end["p90"] = s.end_to_end_ms[1];
  end_to_end["p99"] = s.end_to_end_ms[2];
  end_to_end["max"] = s.end_to_end_ms[3];
  d["end_to_end_ms"] = end_to_end;
  d["ate_rmse_m"] = optionalNumber(s.ate_rmse_m);
  d["rte_rmse_m"] = optionalNumber(s.rte_rmse_m);
  d["stopped"] = s.stopped;
  d["error"] = s.error;
  d["failure"] = s.failure;
  d["warnings"] = s.warnings;
  d["report"] = s.report;
  d["latency_report"] = s.latency_report;
  return d;
}

}  // namespace voca_python
