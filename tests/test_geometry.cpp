#include <doctest/doctest.h>

#include "voca/geometry/se3.h"

using voca::SE3d;
using voca::SO3d;

TEST_CASE("SO3 exp/log round trip") {
  for (const Eigen::Vector3d& omega : {Eigen::Vector3d(0.1, -0.2, 0.3), Eigen::Vector3d(1e-9, 2e-9, -1e-9),
                                      Eigen::Vector3d(0.0, 3.0, 0.1)}) {
    CHECK((SO3d::exp(omega).log() - omega).norm() < 1e-12);
  }
}

TEST_CASE("SE3 exp/log round trip and inverse") {
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.5, -1.0, 2.0, 0.3, -0.1, 0.7;
  const SE3d t = SE3d::exp(xi);
  CHECK((t.log() - xi).norm() < 1e-12);
  CHECK(((t * t.inverse()).matrix() - Eigen::Matrix4d::Identity()).norm() < 1e-12);
}
