#include "formats/trajectory/trajectory_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include "formats/trajectory/trajectory_writer.h"
#include "platform/filesystem/output_paths.h"
#include "voca/core/error.h"

namespace voca {

namespace {

using Path = std::filesystem::path;

// One non-empty, non-comment line of a text file with its 1-based line number.
struct Row {
  int line = 0;
  std::string text;
};

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// Data rows of a text file; blank lines and '#' comments are skipped.
std::vector<Row> readRows(const Path& path) {
  requireNotDevice(path, "trajectory file");
  std::ifstream in(path);
  if (!in) throw InputError(fmt::format("cannot open trajectory file {}", path.string()));
  std::vector<Row> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string_view body = trim(line);
    if (body.empty() || body.front() == '#') continue;
    rows.push_back({number, std::string(body)});
  }
  if (in.bad()) throw InputError(fmt::format("error reading {}", path.string()));
  return rows;
}

std::vector<std::string_view> splitWhitespace(std::string_view s) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t') ++i;
    if (i > start) fields.push_back(s.substr(start, i - start));
  }
  return fields;
}

std::vector<std::string_view> splitCommas(std::string_view s) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = s.find(',', start);
    fields.push_back(trim(s.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

std::string where(const Path& path, int line) { return fmt::format("{}:{}", path.string(), line); }

double parseNumber(std::string_view field, const Path& path, int line, std::string_view name) {
  std::string_view text = field;
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value) || text.empty()) {
    throw InputError(fmt::format("{}: {} '{}' is not a finite number", where(path, line), name, field));
  }
  return value;
}

int64_t parseSeconds(std::string_view field, const Path& path, int line) {
  const std::optional<int64_t> t_ns = parseSecondsToNs(field);
  if (!t_ns) {
    throw InputError(
        fmt::format("{}: timestamp '{}' is not a number of seconds within range", where(path, line), field));
  }
  return *t_ns;
}

int64_t parseIntegerNs(std::string_view field, const Path& path, int line) {
  int64_t value = 0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc() || end != field.data() + field.size() || field.empty()) {
    throw InputError(
        fmt::format("{}: timestamp '{}' is not an integer number of nanoseconds", where(path, line), field));
  }
  return value;
}

Eigen::Quaterniond makeQuaternion(double w, double x, double y, double z, const Path& path, int line) {
  const Eigen::Quaterniond q(w, x, y, z);
  // Files round quaternions to a few digits, so only a degenerate one is an error; SO3 normalises.
  if (!(q.norm() > 1e-6)) {
    throw InputError(fmt::format("{}: quaternion ({} {} {} {}) has zero length", where(path, line), w, x, y, z));
  }
  return q;
}

// Repeated timestamps occur in real estimates (evo's V102.txt has four); going back in time is an error.
void requireIncreasing(const Trajectory& trajectory, const Path& path, int line) {
  const std::size_t n = trajectory.poses.size();
  if (n >= 2 && trajectory.poses[n - 1].t_ns < trajectory.poses[n - 2].t_ns) {
    throw InputError(fmt::format("{}: timestamp {} ns is before the previous row's {} ns", where(path, line),
                                 trajectory.poses[n - 1].t_ns, trajectory.poses[n - 2].t_ns));
  }
}

Trajectory parseTum(const Path& path, const std::vector<Row>& rows) {
  Trajectory trajectory;
  trajectory.poses.reserve(rows.size());
  for (const Row& row : rows) {
    const std::vector<std::string_view> f = splitWhitespace(row.text);
    if (f.size() != 8) {
      throw InputError(fmt::format("{}: expected 8 space-separated fields (TUM: t tx ty tz qx qy qz qw), found {}",
                                   where(path, row.line), f.size()));
    }
    std::array<double, 7> v{};
    static constexpr std::array<const char*, 7> kNames = {"tx", "ty", "tz", "qx", "qy", "qz", "qw"};
    for (int i = 0; i < 7; ++i) v[i] = parseNumber(f[i + 1], path, row.line, kNames[i]);
    const Eigen::Quaterniond q = makeQuaternion(v[6], v[3], v[4], v[5], path, row.line);
    trajectory.poses.push_back({parseSeconds(f[0], path, row.line), SE3d(q, Eigen::Vector3d(v[0], v[1], v[2]))});
    requireIncreasing(trajectory, path, row.line);
  }
  return trajectory;
}

bool startsWithInteger(std::string_view field) {
  if (!field.empty() && (field.front() == '-' || field.front() == '+')) field.remove_prefix(1);
  return !field.empty() && field.front() >= '0' && field.front() <= '9';
}

Trajectory parseEuroc(const Path& path, const std::vector<Row>& rows) {
  Trajectory trajectory;
  trajectory.poses.reserve(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Row& row = rows[r];
    const std::vector<std::string_view> f = splitCommas(row.text);
    // EuRoC's own header starts with '#'; other tools write "timestamp,..." without it.
    if (r == 0 && !f.empty() && !startsWithInteger(f[0])) continue;
    if (f.size() < 8) {
      throw InputError(
          fmt::format("{}: expected at least 8 comma-separated fields (EuRoC: t_ns,px,py,pz,qw,qx,qy,qz), found {}",
                      where(path, row.line), f.size()));
    }
    std::array<double, 7> v{};
    static constexpr std::array<const char*, 7> kNames = {"px", "py", "pz", "qw", "qx", "qy", "qz"};
    for (int i = 0; i < 7; ++i) v[i] = parseNumber(f[i + 1], path, row.line, kNames[i]);
    const Eigen::Quaterniond q = makeQuaternion(v[3], v[4], v[5], v[6], path, row.line);
    trajectory.poses.push_back({parseIntegerNs(f[0], path, row.line), SE3d(q, Eigen::Vector3d(v[0], v[1], v[2]))});
    requireIncreasing(trajectory, path, row.line);
  }
  return trajectory;
}

Trajectory parseKitti(const Path& path, const std::vector<Row>& rows, const Path& times_path) {
  Trajectory trajectory;
  trajectory.poses.reserve(rows.size());
  for (const Row& row : rows) {
    const std::vector<std::string_view> f = splitWhitespace(row.text);
    if (f.size() != 12) {
      throw InputError(fmt::format("{}: expected 12 space-separated numbers (KITTI: 3x4 pose, row-major), found {}",
                                   where(path, row.line), f.size()));
    }
    Eigen::Matrix<double, 3, 4> m;
    for (int i = 0; i < 12; ++i) m(i / 4, i % 4) = parseNumber(f[i], path, row.line, fmt::format("entry {}", i + 1));
    const Eigen::Matrix3d r = m.leftCols<3>();
    // KITTI files keep about 7 digits, so rotations are orthonormal only to ~1e-6.
    if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-3 || r.determinant() < 0.0) {
      throw InputError(fmt::format("{}: the left 3x3 block is not a rotation matrix", where(path, row.line)));
    }
    const int64_t index = static_cast<int64_t>(trajectory.poses.size());
    trajectory.poses.push_back({index * 1'000'000'000, SE3d(m)});
    trajectory.raw_matrices.push_back(m);
  }
  trajectory.has_timestamps = false;
  if (!times_path.empty()) {
    const std::vector<int64_t> times = loadTimesFile(times_path);
    if (times.size() != trajectory.poses.size()) {
      throw InputError(fmt::format("{} has {} times but {} has {} poses", times_path.string(), times.size(),
                                   path.string(), trajectory.poses.size()));
    }
    for (std::size_t i = 0; i < times.size(); ++i) trajectory.poses[i].t_ns = times[i];
    trajectory.has_timestamps = true;
  }
  return trajectory;
}

TrajectoryFormat detectFromRows(const Path& path, const std::vector<Row>& rows) {
  if (rows.empty()) throw InputError(fmt::format("{} contains no poses", path.string()));
  const Row& row = rows.front();
  if (row.text.find(',') != std::string::npos) return TrajectoryFormat::kEuroc;
  const std::size_t fields = splitWhitespace(row.text).size();
  if (fields == 8) return TrajectoryFormat::kTum;
  if (fields == 12) return TrajectoryFormat::kKitti;
  throw InputError(
      fmt::format("{}: cannot tell the trajectory format: {} space-separated fields, expected 8 (TUM) or 12 "
                  "(KITTI), or comma-separated EuRoC csv",
                  where(path, row.line), fields));
}

}  // namespace

std::string_view trajectoryFormatName(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kEuroc:
      return "euroc";
    case TrajectoryFormat::kKitti:
      return "kitti";
  }
  return "unknown";
}

std::optional<TrajectoryFormat> parseTrajectoryFormat(std::string_view name) {
  if (name == "tum") return TrajectoryFormat::kTum;
  if (name == "euroc") return TrajectoryFormat::kEuroc;
  if (name == "kitti") return TrajectoryFormat::kKitti;
  return std::nullopt;
}

std::optional<int64_t> parseSecondsToNs(std::string_view text) {
  std::size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) negative = text[i++] == '-';
  std::string digits;
  int64_t exponent = 0;  // value = digits * 10^exponent
  bool any_digit = false;
  while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
    digits += text[i++];
    any_digit = true;
  }
  if (i < text.size() && text[i] == '.') {
    ++i;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
      digits += text[i++];
      --exponent;
      any_digit = true;
    }
  }
  if (!any_digit) return std::nullopt;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    bool exp_negative = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) exp_negative = text[i++] == '-';
    int64_t e = 0;
    bool exp_digit = false;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
      e = std::min<int64_t>(e * 10 + (text[i++] - '0'), 100000);  // saturate: huge exponents overflow anyway
      exp_digit = true;
    }
    if (!exp_digit) return std::nullopt;
    exponent += exp_negative ? -e : e;
  }
  if (i != text.size()) return std::nullopt;

  const std::size_t first_nonzero = digits.find_first_not_of('0');
  if (first_nonzero == std::string::npos) return 0;
  digits.erase(0, first_nonzero);

  // ns = digits * 10^(exponent + 9), rounded half away from zero where digits are dropped.
  const int64_t shift = exponent + 9;
  std::size_t keep = digits.size();
  bool round_up = false;
  if (shift < 0) {
    const int64_t kept = static_cast<int64_t>(digits.size()) + shift;
    if (kept < 0) return 0;
    keep = static_cast<std::size_t>(kept);
    round_up = keep < digits.size() && digits[keep] >= '5';
  }
  int64_t value = 0;
  for (std::size_t d = 0; d < keep; ++d) {
    if (__builtin_mul_overflow(value, int64_t{10}, &value) || __builtin_add_overflow(value, digits[d] - '0', &value)) {
      return std::nullopt;
    }
  }
  for (int64_t s = 0; s < shift; ++s) {
    if (__builtin_mul_overflow(value, int64_t{10}, &value)) return std::nullopt;
  }
  if (round_up && __builtin_add_overflow(value, int64_t{1}, &value)) return std::nullopt;
  return negative ? -value : value;
}

TrajectoryFormat detectTrajectoryFormat(const Path& path) { return detectFromRows(path, readRows(path)); }

std::vector<int64_t> loadTimesFile(const Path& path) {
  std::vector<int64_t> times;
  for (const Row& row : readRows(path)) {
    const std::vector<std::string_view> f = splitWhitespace(row.text);
    if (f.size() != 1) {
      throw InputError(
          fmt::format("{}: expected one time in seconds per line, found {} fields", where(path, row.line), f.size()));
    }
    times.push_back(parseSeconds(f[0], path, row.line));
    if (times.size() >= 2 && times.back() < times[times.size() - 2]) {
      throw InputError(fmt::format("{}: time {} is before the previous line's", where(path, row.line), f[0]));
    }
  }
  return times;
}

Trajectory loadTrajectory(const Path& path, std::optional<TrajectoryFormat> format, const Path& kitti_times) {
  const std::vector<Row> rows = readRows(path);
  if (rows.empty()) throw InputError(fmt::format("{} contains no poses", path.string()));
  const TrajectoryFormat chosen = format ? *format : detectFromRows(path, rows);
  if (!kitti_times.empty() && chosen != TrajectoryFormat::kKitti) {
    throw InputError(fmt::format("a times file was given for {}, but only KITTI trajectories take one ({} is {})",
                                 path.string(), path.filename().string(), trajectoryFormatName(chosen)));
  }
  Trajectory trajectory;
  switch (chosen) {
    case TrajectoryFormat::kTum:
      trajectory = parseTum(path, rows);
      break;
    case TrajectoryFormat::kEuroc:
      trajectory = parseEuroc(path, rows);
      break;
    case TrajectoryFormat::kKitti:
      trajectory = parseKitti(path, rows, kitti_times);
      break;
  }
  if (trajectory.poses.empty()) throw InputError(fmt::format("{} contains no poses", path.string()));
  return trajectory;
}

void saveTrajectory(const Trajectory& trajectory, const Path& path, TrajectoryFormat format) {
  TrajectoryWriter writer(path, format);
  for (const TimedPose& pose : trajectory.poses) writer.append(pose);
  writer.close();
}

}  // namespace voca
