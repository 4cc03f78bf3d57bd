#include "formats/dataset/dataset.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <unordered_map>

#include "formats/calib/calibration_io.h"
#include "formats/image/png_io.h"
#include "formats/trajectory/trajectory_io.h"
#include "voca/core/error.h"

namespace voca {
namespace fs = std::filesystem;

namespace {

constexpr int kWarningExamples = 3;
// Below INT64_MAX nanoseconds (9.22e9 s) with room for the rounding of the product.
constexpr double kMaxSeconds = 9.0e9;

std::string_view trim(std::string_view s) {
  const auto not_space = [](char c) { return c != ' ' && c != '\t' && c != '\r' && c != '\n'; };
  while (!s.empty() && !not_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && !not_space(s.back())) s.remove_suffix(1);
  return s;
}

bool parseInt64(std::string_view text, int64_t& value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

bool parseDouble(std::string_view text, double& value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size() && std::isfinite(value);
}

// Non-empty, non-comment lines of a text file with their 1-based line numbers.
struct Line {
  int number = 0;
  std::string text;
};

std::vector<Line> readLines(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open");
  std::vector<Line> lines;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string_view content = trim(line);
    if (content.empty() || content.front() == '#') continue;
    lines.push_back({number, std::string(content)});
  }
  if (in.bad()) throw InputError(path.string() + ": read error");
  return lines;
}

std::string where(const fs::path& file, int line) { return file.string() + ":" + std::to_string(line); }

struct CsvRow {
  int64_t t_ns = 0;
  std::string file;
};

// camN/data.csv: "<timestamp ns>,<file name>" per row (the file name is optional for videos),
// timestamps strictly increasing because frames are replayed in this order.
std::vector<CsvRow> readCameraCsv(const fs::path& csv, bool need_file) {
  if (!fs::is_regular_file(csv)) throw InputError(csv.string() + ": missing (every camera needs its data.csv)");
  std::vector<CsvRow> rows;
  for (const Line& line : readLines(csv)) {
    const std::string_view text = line.text;
    const size_t comma = text.find(',');
    const std::string_view stamp = trim(text.substr(0, comma));
    const std::string_view file = comma == std::string_view::npos ? std::string_view() : trim(text.substr(comma + 1));
    CsvRow row;
    if (!parseInt64(stamp, row.t_ns) || row.t_ns < 0 || (need_file && file.empty()) ||
        file.find(',') != std::string_view::npos) {
      throw InputError(where(csv, line.number) + ": expected '<timestamp ns>," +
                       (need_file ? "<image file name>" : "[file name]") + "', got '" + line.text + "'");
    }
    if (!rows.empty() && row.t_ns <= rows.back().t_ns) {
      throw InputError(where(csv, line.number) + ": timestamp " + std::to_string(row.t_ns) +
                       " is not after the previous row's " + std::to_string(rows.back().t_ns));
    }
    row.file = std::string(file);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string examples(const std::vector<std::string>& items) {
  std::string out;
  for (size_t i = 0; i < items.size() && i < kWarningExamples; ++i) out += (i == 0 ? "" : ", ") + items[i];
  if (items.size() > kWarningExamples) out += ", ...";
  return out;
}

void readEuroc(const fs::path& mav0, Dataset& dataset) {
  struct Camera {
    std::vector<CsvRow> rows;
    std::vector<fs::path> images;  // per row; empty when the file is missing
  };
  Camera cams[2];
  for (int c = 0; c < 2; ++c) {
    const fs::path cam_dir = mav0 / ("cam" + std::to_string(c));
    const fs::path csv = cam_dir / "data.csv";
    Camera& cam = cams[c];
    cam.rows = readCameraCsv(csv, true);
    std::vector<std::string> missing;
    for (const CsvRow& row : cam.rows) {
      fs::path image = cam_dir / "data" / row.file;
      if (fs::is_regular_file(image)) {
        cam.images.push_back(std::move(image));
      } else {
        cam.images.emplace_back();
        missing.push_back("data/" + row.file);
      }
    }
    if (!missing.empty()) {
      dataset.warnings.push_back(csv.string() + ": " + std::to_string(missing.size()) + " of " +
                                 std::to_string(cam.rows.size()) + " rows have no image file and were skipped (" +
                                 examples(missing) + ")");
    }
  }

  std::unordered_map<int64_t, size_t> right_by_time;
  for (size_t i = 0; i < cams[1].rows.size(); ++i) {
    if (!cams[1].images[i].empty()) right_by_time.emplace(cams[1].rows[i].t_ns, i);
  }
  std::vector<std::string> unpaired_left;
  for (size_t i = 0; i < cams[0].rows.size(); ++i) {
    if (cams[0].images[i].empty()) continue;
    const auto match = right_by_time.find(cams[0].rows[i].t_ns);
    if (match == right_by_time.end()) {
      unpaired_left.push_back(std::to_string(cams[0].rows[i].t_ns));
      continue;
    }
    dataset.frames.push_back({cams[0].rows[i].t_ns, cams[0].images[i], cams[1].images[match->second]});
    right_by_time.erase(match);
  }
  if (!unpaired_left.empty()) {
    dataset.warnings.push_back(std::to_string(unpaired_left.size()) +
                               " cam0 images have no cam1 image with the same timestamp and were skipped (t_ns " +
                               examples(unpaired_left) + ")");
  }
  if (!right_by_time.empty()) {
    std::vector<int64_t> stamps;
    for (const auto& [t_ns, index] : right_by_time) stamps.push_back(t_ns);
    std::sort(stamps.begin(), stamps.end());
    std::vector<std::string> unpaired_right;
    for (int64_t t : stamps) unpaired_right.push_back(std::to_string(t));
    dataset.warnings.push_back(std::to_string(unpaired_right.size()) +
                               " cam1 images have no cam0 image with the same timestamp and were skipped (t_ns " +
                               examples(unpaired_right) + ")");
  }
  if (dataset.frames.empty()) {
    throw InputError(mav0.string() + ": no stereo frame: no timestamp has an image in both cam0/data and cam1/data");
  }
}

void readVocaVideo(const fs::path& mav0, Dataset& dataset) {
  dataset.video_left = mav0 / "cam0" / "data.mp4";
  dataset.video_right = mav0 / "cam1" / "data.mp4";
  if (!fs::is_regular_file(dataset.video_right)) {
    throw InputError(dataset.video_right.string() + ": missing (the VOCA video layout needs cam0 and cam1 videos)");
  }
  const std::vector<CsvRow> left = readCameraCsv(mav0 / "cam0" / "data.csv", false);
  const std::vector<CsvRow> right = readCameraCsv(mav0 / "cam1" / "data.csv", false);
  // Frame i of each video is row i of its data.csv, so the cameras pair by row.
  const size_t count = std::min(left.size(), right.size());
  if (left.size() != right.size()) {
    dataset.warnings.push_back("cam0/data.csv has " + std::to_string(left.size()) + " rows and cam1/data.csv " +
                               std::to_string(right.size()) + "; the cameras pair by row, so only the first " +
                               std::to_string(count) + " rows count");
  }
  int mismatched = 0;
  for (size_t i = 0; i < count; ++i) {
    if (left[i].t_ns != right[i].t_ns) ++mismatched;
    dataset.frames.push_back({left[i].t_ns, {}, {}});
  }
  if (mismatched > 0) {
    dataset.warnings.push_back(std::to_string(mismatched) +
                               " rows of cam0/data.csv and cam1/data.csv have different timestamps; using cam0's");
  }
  if (dataset.frames.empty()) throw InputError((mav0 / "cam0" / "data.csv").string() + ": no frames listed");
}

void readKitti(const fs::path& root, Dataset& dataset) {
  for (const char* sub : {"image_0", "image_1"}) {
    if (!fs::is_directory(root / sub))
      throw InputError((root / sub).string() + ": missing (KITTI stereo needs image_0 and image_1)");
  }
  const fs::path times = root / "times.txt";
  std::vector<std::string> missing;
  int index = 0;
  for (const Line& line : readLines(times)) {
    double seconds = 0.0;
    // int64 nanoseconds end after ~292 years; llround of a larger value is undefined, not an error.
    if (!parseDouble(line.text, seconds) || seconds < 0.0 || seconds >= kMaxSeconds) {
      throw InputError(where(times, line.number) + ": expected a time in seconds, got '" + line.text + "'");
    }
    const int64_t t_ns = std::llround(seconds * 1e9);
    if (!dataset.frames.empty() && t_ns <= dataset.frames.back().t_ns) {
      throw InputError(where(times, line.number) + ": time " + line.text + " s is not after the previous line's");
    }
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", index++);
    fs::path left = root / "image_0" / name;
    fs::path right = root / "image_1" / name;
    const bool have_left = fs::is_regular_file(left);
    const bool have_right = fs::is_regular_file(right);
    if (have_left && have_right) {
      dataset.frames.push_back({t_ns, std::move(left), std::move(right)});
    } else {
      missing.push_back((have_left ? "image_1/" : "image_0/") + std::string(name));
    }
  }
  if (!missing.empty()) {
    dataset.warnings.push_back(times.string() + ": " + std::to_string(missing.size()) + " of " + std::to_string(index) +
                               " frames lack an image and were skipped (" + examples(missing) + ")");
  }
  if (dataset.frames.empty()) throw InputError(root.string() + ": no KITTI frame has both image_0 and image_1 images");

  const fs::path sequence = root.filename();
  const fs::path candidates[] = {root.parent_path().parent_path() / "poses" / (sequence.string() + ".txt"),
                                 root / "poses.txt"};
  for (const fs::path& candidate : candidates) {
    if (!sequence.empty() && fs::is_regular_file(candidate)) {
      dataset.ground_truth = candidate;
      break;
    }
  }
  if (fs::is_regular_file(root / "calib.txt")) dataset.calibration = root / "calib.txt";
}

}  // namespace

std::string_view layoutName(DatasetLayout layout) {
  switch (layout) {
    case DatasetLayout::kEuroc:
      return "EuRoC";
    case DatasetLayout::kKitti:
      return "KITTI";
    case DatasetLayout::kVocaVideo:
      return "VOCA video";
  }
  return "unknown";
}

Dataset openDataset(const fs::path& path) {
  if (!fs::exists(path)) throw InputError(path.string() + ": dataset folder not found");
  if (!fs::is_directory(path)) throw InputError(path.string() + ": not a folder (a dataset is a folder)");
  Dataset dataset;
  // Without a trailing separator, so filename() is the folder's name (KITTI's sequence number).
  dataset.root = path.lexically_normal();
  if (dataset.root.filename().empty()) dataset.root = dataset.root.parent_path();
  const fs::path& root = dataset.root;

  fs::path mav0;
  if (fs::is_directory(root / "mav0")) {
    mav0 = root / "mav0";
  } else if (fs::is_directory(root / "cam0")) {
    mav0 = root;
  }
  if (!mav0.empty() && fs::is_regular_file(mav0 / "cam0" / "data.mp4")) {
    dataset.layout = DatasetLayout::kVocaVideo;
    readVocaVideo(mav0, dataset);
  } else if (!mav0.empty() && fs::exists(mav0 / "cam0" / "data.csv")) {
    dataset.layout = DatasetLayout::kEuroc;
    readEuroc(mav0, dataset);
  } else if (!mav0.empty() && fs::is_regular_file(mav0 / "cam1" / "data.mp4")) {
    // `voca encode --cameras 1` writes the right camera alone.
    throw InputError((mav0 / "cam0" / "data.mp4").string() +
                     ": missing (the VOCA video layout needs cam0 and cam1 videos; this folder holds cam1's alone)");
  } else if (fs::is_directory(root / "image_0") && fs::exists(root / "times.txt")) {
    dataset.layout = DatasetLayout::kKitti;
    readKitti(root, dataset);
    return dataset;
  } else {
    throw InputError(path.string() +
                     ": unknown dataset layout: looked for mav0/cam0/data.csv (EuRoC, TUM-VI), mav0/cam0/data.mp4 "
                     "(VOCA video) and image_0/ with times.txt (KITTI odometry sequence)");
  }

  const fs::path ground_truth = mav0 / "state_groundtruth_estimate0" / "data.csv";
  if (fs::is_regular_file(ground_truth)) dataset.ground_truth = ground_truth;
  std::vector<fs::path> beside = {root};
  if (mav0 == root) beside.push_back(root.parent_path());
  for (const fs::path& folder : beside) {
    dataset.calibration = findCalibrationJson(folder);
    if (dataset.calibration) break;
  }
  if (!dataset.calibration && fs::is_regular_file(mav0 / "cam0" / "sensor.yaml")) dataset.calibration = mav0;
  return dataset;
}

std::vector<NamedPath> datasetReadPaths(const Dataset& dataset) {
  std::vector<NamedPath> paths;
  const std::filesystem::path& root = dataset.root;
  if (dataset.layout == DatasetLayout::kKitti) {
    for (const char* part : {"image_0", "image_1", "times.txt", "calib.txt"}) {
      paths.push_back({"the dataset's " + std::string(part), root / part});
    }
  } else {
    paths.push_back({"the dataset's mav0 folder", root.filename() == "mav0" ? root : root / "mav0"});
  }
  if (dataset.ground_truth) paths.push_back({"the ground truth", *dataset.ground_truth});
  return paths;
}

std::optional<Trajectory> loadGroundTruth(const Dataset& dataset, const std::optional<std::filesystem::path>& file) {
  const std::optional<std::filesystem::path>& path = file ? file : dataset.ground_truth;
  if (!path) return std::nullopt;
  // The sequence's own poses file is KITTI's; a file given instead may be in any format.
  if (dataset.layout == DatasetLayout::kKitti && (!file || detectTrajectoryFormat(*path) == TrajectoryFormat::kKitti)) {
    return loadTrajectory(*path, TrajectoryFormat::kKitti, dataset.root / "times.txt");
  }
  return loadTrajectory(*path);
}

EurocWriter::EurocWriter(const fs::path& root, int num_cameras) : mav0_(root / "mav0") {
  if (num_cameras < 1) throw InputError("EurocWriter: need at least one camera, got " + std::to_string(num_cameras));
  for (int c = 0; c < num_cameras; ++c) {
    const fs::path cam_dir = mav0_ / ("cam" + std::to_string(c));
    std::error_code ec;
    fs::create_directories(cam_dir / "data", ec);
    if (ec) throw InputError((cam_dir / "data").string() + ": cannot create folder: " + ec.message());
    // A sequence written over another replaces it: data.csv is rewritten, and the old images it no
    // longer lists would stay beside the new ones, for tools that read the folder to mix up.
    std::vector<fs::path> old_images;
    for (const fs::directory_entry& entry : fs::directory_iterator(cam_dir / "data", ec)) {
      if (entry.is_regular_file(ec) && entry.path().extension() == ".png") old_images.push_back(entry.path());
    }
    for (const fs::path& image : old_images) fs::remove(image, ec);
    csv_.emplace_back(cam_dir / "data.csv", std::ios::trunc);
    if (!csv_.back()) throw InputError((cam_dir / "data.csv").string() + ": cannot open for writing");
    csv_.back() << "#timestamp [ns],filename\n";
  }
}

EurocWriter::~EurocWriter() {
  try {
    finish();
  } catch (const std::exception&) {
    // A destructor cannot report; callers who care call finish() themselves.
  }
}

void EurocWriter::addFrame(int64_t t_ns, std::span<const GrayView> images) {
  if (finished_) throw InputError(mav0_.string() + ": EurocWriter::addFrame after finish()");
  if (images.size() != csv_.size()) {
    throw InputError(mav0_.string() + ": expected " + std::to_string(csv_.size()) + " images per frame, got " +
                     std::to_string(images.size()));
  }
  if (t_ns < 0 || (frame_count_ > 0 && t_ns <= last_t_ns_)) {
    throw InputError(mav0_.string() + ": frame timestamp " + std::to_string(t_ns) + " is not after the previous " +
                     std::to_string(last_t_ns_));
  }
  const std::string name = std::to_string(t_ns) + ".png";
  for (size_t c = 0; c < csv_.size(); ++c) {
    writePngGray(mav0_ / ("cam" + std::to_string(c)) / "data" / name, images[c]);
    csv_[c] << t_ns << ',' << name << '\n';
  }
  last_t_ns_ = t_ns;
  ++frame_count_;
}

void EurocWriter::finish() {
  if (finished_) return;
  finished_ = true;
  for (size_t c = 0; c < csv_.size(); ++c) {
    csv_[c].close();
    if (!csv_[c]) {
      throw InputError((mav0_ / ("cam" + std::to_string(c)) / "data.csv").string() + ": write failed (disk full?)");
    }
  }
}

}  // namespace voca
