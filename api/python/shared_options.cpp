#include "shared_options.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <type_traits>

#include "conversions.h"

namespace py = pybind11;

namespace voca_python {
namespace {

struct SharedOption {
  const char* name;
  const char* description;
  const char* python_type;                            // what a value must be, for the TypeError
  void (*set)(voca_rt::Options&, const py::handle&);  // raises py::cast_error for the wrong type
  py::object (*get)(const voca_rt::Options&);         // for the documented default
};

template <typename T>
constexpr const char* pythonType() {
  if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, std::optional<bool>>) {
    return "bool";
  } else if constexpr (std::is_integral_v<T>) {
    return "int";
  } else if constexpr (std::is_floating_point_v<T>) {
    return "float";
  } else {
    static_assert(std::is_same_v<T, std::string>);
    return "str";
  }
}

// The option stored in Options::*Field, taking a Python value of the field's type.
template <auto Field>
SharedOption valueOption(const char* name, const char* description) {
  using T = std::remove_cvref_t<decltype(std::declval<voca_rt::Options&>().*Field)>;
  return {name, description, pythonType<T>(),
          [](voca_rt::Options& options, const py::handle& value) { options.*Field = value.cast<T>(); },
          [](const voca_rt::Options& options) { return py::cast(options.*Field); }};
}

// A file option: any str or os.PathLike (pathlib.Path) names the file.
template <std::string voca_rt::Options::*Field>
SharedOption pathOption(const char* name, const char* description) {
  return {name, description, "str or os.PathLike",
          [](voca_rt::Options& options, const py::handle& value) {
            options.*Field = value.cast<std::filesystem::path>().string();
          },
          [](const voca_rt::Options& options) { return py::cast(options.*Field); }};
}

using voca_rt::Options;

const std::array kSharedOptions = {
    pathOption<&Options::config>("config",
                                 "shipped config name (euroc, tumvi, kitti) or a JSON config file; "
                                 "None: euroc"),
    valueOption<&Options::mode>("mode",
                                "prior mode: none, mv, of_then_mv, mv_then_of, mv_parallel_of; None: the "
                                "config's"),
    valueOption<&Options::bridge_iframes>("bridge_iframes",
                                          "reuse the last P-frame's motion on I-frames (--bridge); "
                                          "None: the config's"),
    valueOption<&Options::max_points>("max_points", "tracker capacity per camera"),
    valueOption<&Options::threads>("threads",
                                   "0: one thread per stage; 1: every stage on one thread; N: stages "
                                   "grouped on N threads"),
    valueOption<&Options::frontend_threads>("frontend_threads",
                                            "0: automatic; 1 or 2 (a helper thread takes about "
                                            "half the points)"),
    valueOption<&Options::pins>("pins", "stage-to-core map (--pin), \"decode:0,frontend:0,backend:1\""),
    valueOption<&Options::scheduling>("scheduling",
                                      "other, fifo or rr (--sched; real-time classes need "
                                      "CAP_SYS_NICE)"),
    valueOption<&Options::priority>("priority", "1-99, with fifo and rr"),
    valueOption<&Options::lock_memory>("lock_memory", "mlockall before the first frame (--mlock)"),
    valueOption<&Options::strict>("strict", "a damaged frame stops the run instead of being skipped"),
    valueOption<&Options::decoder>("decoder", "auto, software, vaapi, v4l2m2m"),
    valueOption<&Options::skip_deblock>("skip_deblock", "software decoding without H.264's loop filter"),
    pathOption<&Options::trajectory_file>("trajectory_file", "also write each pose there as it is estimated (--out)"),
    valueOption<&Options::trajectory_format>("trajectory_format", "tum, euroc or kitti (--format)"),
    pathOption<&Options::statistics_file>("statistics_file", "JSON statistics written when the run ends (--stats)"),
    pathOption<&Options::trace_file>("trace_file", "Chrome trace of every frame's stages (--trace)"),
    valueOption<&Options::progress>("progress", "progress lines on stderr"),
};

}  // namespace

void setSharedOption(voca_rt::Options& options, const std::string& name, const py::handle& value,
                     const char* function) {
  for (const SharedOption& option : kSharedOptions) {
    if (name != option.name) continue;
    if (value.is_none()) return;
    try {
      option.set(options, value);
    } catch (const py::cast_error&) {
      throw py::type_error(std::string(function) + "(): " + name + " takes " + option.python_type + ", not " +
                           typeName(value));
    }
    return;
  }
  throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" + name + "'");
}

void setSharedOptions(voca_rt::Options& options, const py::kwargs& keywords, const char* function) {
  for (const auto& [name, value] : keywords) setSharedOption(options, py::cast<std::string>(name), value, function);
}

std::string sharedOptionsDoc() {
  const voca_rt::Options defaults;
  std::string doc;
  for (const SharedOption& option : kSharedOptions) {
    const py::object value = option.get(defaults);
    const bool unset = value.is_none() || (py::isinstance<py::str>(value) && py::len(value) == 0);
    std::string entry = "  " + std::string(option.name) + "=" + (unset ? "None" : std::string(py::repr(value)));
    entry.resize(std::max<std::size_t>(entry.size() + 2, 26), ' ');
    doc += entry + option.description + "\n";
  }
  return doc;
}

}  // namespace voca_python
