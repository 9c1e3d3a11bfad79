// The floor of the far rows' alignment (tracking/object_lidar_align.hpp): the scale that puts a
// track's origin on the face its LiDAR returns measure (a quantile of their depths), from the
// reported far rows that kept returns, in the camera frame of each row's own pose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "tracking/object_lidar_align.hpp"

namespace twistslam {
namespace {

// A row at `depth` m straight ahead of a camera at world x = camera_x, with `returns` LiDAR
// returns at return_depth m (0: none kept).
objects::TrackFrame far_row(int frame, double camera_x, double depth, double return_depth,
                            int returns = 21, bool reported = true) {
  objects::TrackFrame row;
  row.frame = frame;
  row.reported = reported;
  row.T_w_o = Mat4::Identity();
  row.T_w_o.topRightCorner<3, 1>() = Vec3(camera_x, 0.0, depth);
  row.far_lidar_returns.resize(returns, 3);
  for (int i = 0; i < returns; ++i)  // 0.05 m apart around return_depth (21: +-0.5 m)
    row.far_lidar_returns.row(i) << 600.0 + i, 180.0, return_depth + (i - returns / 2) * 0.05;
  return row;
}

std::map<int, Mat4> cameras_at_x(int frames, double step_x) {
  std::map<int, Mat4> T_c_w;
  for (int f = 0; f < frames; ++f) {
    T_c_w[f] = Mat4::Identity();
    T_c_w[f](0, 3) = -step_x * f;  // the camera at world x = step_x f
  }
  return T_c_w;
}

TEST(FarSurfaceFloor, TheMedianRowSaysHowFarTheOriginMayComeNearer) {
  objects::ObjectTrack track;
  const double origins[] = {54.7, 55.0, 56.0, 57.0, 58.0};
  const double surfaces[] = {56.0, 56.1, 56.5, 57.5, 60.0};
  for (int f = 0; f < 5; ++f) track.frames.push_back(far_row(f, 2.0 * f, origins[f], surfaces[f]));
  const std::map<int, Mat4> T_c_w = cameras_at_x(5, 2.0);
  std::vector<double> floors;
  for (int f = 0; f < 5; ++f) floors.push_back(surfaces[f] / origins[f]);
  std::sort(floors.begin(), floors.end());
  EXPECT_NEAR(tracking::far_surface_floor(track, T_c_w, 30.0, 0.5), floors[2], 1e-12);
}

TEST(FarSurfaceFloor, TheFaceIsAQuantileOfTheReturnsDepth) {
  objects::ObjectTrack track;
  track.frames.push_back(far_row(0, 0.0, 50.0, 52.0, 21));  // 21 returns 51.5 ... 52.5 m
  const std::map<int, Mat4> T_c_w = cameras_at_x(1, 0.0);
  EXPECT_NEAR(tracking::far_surface_floor(track, T_c_w, 30.0, 0.0), 51.5 / 50.0, 1e-12);
  EXPECT_NEAR(tracking::far_surface_floor(track, T_c_w, 30.0, 0.1), 51.6 / 50.0, 1e-12);
  EXPECT_NEAR(tracking::far_surface_floor(track, T_c_w, 30.0, 1.0), 52.5 / 50.0, 1e-12);
}

TEST(FarSurfaceFloor, NearUnreportedUnposedAndReturnlessRowsDoNotCount) {
  objects::ObjectTrack track;
  track.frames.push_back(far_row(0, 0.0, 50.0, 51.0));                  // counts: 1.02
  track.frames.push_back(far_row(1, 0.0, 20.0, 40.0));                  // nearer than 30 m
  track.frames.push_back(far_row(2, 0.0, 50.0, 80.0, 21, false));       // not reported
  track.frames.push_back(far_row(3, 0.0, 50.0, 80.0, 0));               // no returns kept
  track.frames.push_back(far_row(9, 0.0, 50.0, 80.0));                  // no camera pose
  const std::map<int, Mat4> T_c_w = cameras_at_x(4, 0.0);
  EXPECT_NEAR(tracking::far_surface_floor(track, T_c_w, 30.0, 0.5), 51.0 / 50.0, 1e-12);
  track.frames.erase(track.frames.begin());
  EXPECT_EQ(tracking::far_surface_floor(track, T_c_w, 30.0, 0.5), 0.0) << "no row qualifies";
}

TEST(FarSurfaceFloor, DepthIsTakenInEachRowsCameraFrame) {
  objects::ObjectTrack track;
  // world z 60 m, seen from cameras 0, 10 and 20 m along their optical axis: depths 60, 50
  // and 40 m, each 2 m short of its returns
  for (int f = 0; f < 3; ++f) track.frames.push_back(far_row(f, 0.0, 60.0, 62.0 - 10.0 * f));
  std::map<int, Mat4> T_c_w;
  for (int f = 0; f < 3; ++f) {
    T_c_w[f] = Mat4::Identity();
    T_c_w[f](2, 3) = -10.0 * f;
  }
  EXPECT_NEAR(tracking::far_surface_floor(track, T_c_w, 30.0, 0.5), 52.0 / 50.0, 1e-12);
}

// The scale from the rows' median ratio and the floor (far_align_scale). Urban s19's track 21:
// its points 1.6 % beyond their returns (ratio 0.984) and its origin 2.1 % in front of the face
// they measure (floor 1.021 less the margin): the origin moves onto the face, not nearer.
TEST(FarAlignScale, AnOriginInFrontOfItsFaceMovesOntoIt) {
  EXPECT_DOUBLE_EQ(tracking::far_align_scale(0.984, 1.011, true, 0.15), 1.011);
  EXPECT_DOUBLE_EQ(tracking::far_align_scale(1.005, 1.011, true, 0.15), 1.011) << "farther than the ratio says";
  EXPECT_DOUBLE_EQ(tracking::far_align_scale(1.030, 1.011, true, 0.15), 1.030) << "the ratio goes farther still";
  EXPECT_DOUBLE_EQ(tracking::far_align_scale(0.984, 1.40, true, 0.15), 1.15) << "at most max_ratio";
  // without the lift a nearer move stops at the face, no further (as before the lift)
  EXPECT_DOUBLE_EQ(tracking::far_align_scale(0.984, 1.011, false, 0.15), 1.0);
  EXPECT_DOUBLE_EQ(tracking::far_align_scale(1.005, 1.011, false, 0.15), 1.005);
}

TEST(FarAlignScale, ANearerMoveStopsAtTheFace) {
  for (const bool lift : {true, false}) {
    EXPECT_DOUBLE_EQ(tracking::far_align_scale(0.95, 0.97, lift, 0.15), 0.97) << lift;
    EXPECT_DOUBLE_EQ(tracking::far_align_scale(0.95, 0.90, lift, 0.15), 0.95) << lift << ": the face is nearer";
    EXPECT_DOUBLE_EQ(tracking::far_align_scale(0.95, 0.0, lift, 0.15), 0.95) << lift << ": no floor";
    EXPECT_DOUBLE_EQ(tracking::far_align_scale(1.04, 0.0, lift, 0.15), 1.04) << lift << ": no floor";
  }
}

// The running median a far free-link track's rows move by: a lone outlier row (an occluder's
// returns) does not move its neighbours, NaN rows are skipped, the ends take the rows they have.
TEST(RunningMedian, OutliersAndGapsDoNotMoveTheNeighbours) {
  // of an even count, the upper middle value (detail::median_value)
  const double nan = std::nan("");
  const std::vector<double> ratios = {1.00, 1.01, 0.70, 1.02, nan, 1.03, 1.04};
  const std::vector<double> m = tracking::running_median(ratios, 3);
  ASSERT_EQ(m.size(), ratios.size());
  EXPECT_EQ(m[0], 1.01) << "the first row and its one neighbour";
  EXPECT_EQ(m[1], 1.00);
  EXPECT_EQ(m[2], 1.01) << "the outlier takes its neighbours' ratio";
  EXPECT_EQ(m[3], 1.02) << "0.70 and 1.02: the NaN beside it does not count";
  EXPECT_EQ(m[4], 1.03) << "a NaN row gets its neighbours' median";
  EXPECT_EQ(m[6], 1.04);
  const std::vector<double> wide = tracking::running_median(ratios, 7);
  EXPECT_EQ(wide[2], 1.01) << "rows 0-5 without the NaN: 0.70 1.00 1.01 1.02 1.03";
  EXPECT_EQ(wide[6], 1.03) << "rows 3-6: 1.02 1.03 1.04";
  EXPECT_EQ(tracking::running_median(ratios, 1)[2], 0.70) << "a window of one: the value";
  EXPECT_TRUE(std::isnan(tracking::running_median({nan, nan}, 3)[0])) << "no finite value";
  EXPECT_TRUE(tracking::running_median({}, 7).empty());
}

}  // namespace
}  // namespace twistslam
