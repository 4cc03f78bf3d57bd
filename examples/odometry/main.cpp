// Stereo visual odometry on a recorded VOCA video folder through the VOCA-RT library: reads the
// H.264 access units of both cameras, pushes them into voca_rt::Odometry and prints each estimated
// pose as a TUM row ("t tx ty tz qx qy qz qw", the rows `voca run --out poses.tum` writes).
//
//   voca_example_odometry <video folder> <calibration> [config]
//
// <video folder> is what `voca encode` or `voca record` writes (mav0/camN/data.mp4 + data.csv);
// <calibration> a Basalt JSON, Kalibr YAML, EuRoC sensor.yaml or KITTI calib.txt (`voca encode`
// writes calib.json into the folder); [config] euroc (the default), tumvi, kitti or a JSON file.
// On a robot the access units come from the cameras' encoder instead of the reader.

#include <voca_rt/voca_rt.h>

#include <exception>
#include <iostream>

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::cerr << "usage: " << argv[0] << " <video folder> <calibration> [euroc|tumvi|kitti|config.json]\n";
    return 2;
  }
  try {
    voca_rt::VideoFolderReader reader(argv[1]);

    voca_rt::Options options;
    options.calibration_file = argv[2];
    if (argc == 4) options.config = argv[3];
    options.input = voca_rt::InputKind::kH264;  // compressed frames: motion vectors become tracking priors

    // Without a callback the poses wait for poll(). The offline policy (Options::live false) makes
    // each push wait for room rather than drop a frame, so every run gives the same poses.
    voca_rt::Odometry odometry(options);
    voca_rt::Pose pose;
    const auto print_estimated = [&] {
      while (odometry.poll(pose)) std::cout << voca_rt::tumRow(pose);
    };

    voca_rt::StereoPacket packet;
    while (reader.next(packet)) {
      // Copies the bytes. Throws voca_rt::Error if the pipeline has stopped on bad data (naming the frame).
      odometry.pushH264(packet.t_ns, packet.left.data(), packet.left.size(), packet.right.data(), packet.right.size());
      print_estimated();
    }
    const voca_rt::Summary summary = odometry.finish();  // waits for the last frames' poses
    print_estimated();
    std::cout.flush();

    if (!summary.error.empty() || !summary.failure.empty()) {
      std::cerr << "error: " << (summary.error.empty() ? summary.failure : summary.error) << '\n';
      return 1;
    }
    return 0;
  } catch (const std::exception& error) {  // voca_rt::Error: a missing file, an unusable calibration, ...
    std::cout.flush();
    std::cerr << "error: " << error.what() << '\n';
    return 1;
  }
}
