// Posts read as people (DetectorOptions::person_max_head_ratio): a pole or a tree trunk near
// the sensor is cut flat by the LiDAR's highest beam (+2 deg: 2.0 m at 7.5 m) and passes the
// person height test; its top is as wide as its middle, where a person's head is narrower
// than the shoulders.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "detection/detector.hpp"
#include "detection/person_outline.hpp"
#include "detection_test_helpers.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::detection;
using namespace twistslam::test_scenes;

TEST(PersonOutline, APersonsHeadIsNarrowerThanTheShouldersAPostsTopIsNot) {
  const SceneBox body = person_body(1.5, 9.0);  // shoulders 0.5 m across the line of sight
  const Points3 person_scan = cast_scene({body, head_on(body)});
  const Points3 trunk_scan = cast_scene({post(1.5, 7.0, 0.35, 5.0)});
  auto outline_of = [](const Points3& scan) {
    std::vector<ScenePoint> pts;
    std::vector<int> members;
    float top = -1e9f;
    for (Eigen::Index i = 0; i < scan.rows(); ++i) {
      if (scan(i, 1) > 1.73 - 0.3) continue;  // the road and the returns just above it
      pts.push_back({static_cast<float>(scan(i, 0)), static_cast<float>(scan(i, 2)),
                     static_cast<float>(-scan(i, 1)), static_cast<int>(i)});
      members.push_back(static_cast<int>(pts.size()) - 1);
      top = std::max(top, pts.back().up);
    }
    return person_outline(members, pts, top);
  };
  const PersonOutline person = outline_of(person_scan), trunk = outline_of(trunk_scan);
  EXPECT_NEAR(person.shoulder_width_m, 0.5, 0.08);
  EXPECT_LT(person.head_width_m, 0.6 * person.shoulder_width_m);
  EXPECT_NEAR(trunk.shoulder_width_m, 0.35, 0.08);
  EXPECT_NEAR(trunk.head_width_m, trunk.shoulder_width_m, 0.05);
}

TEST(PersonOutline, PolesAndTrunksCutByTheTopBeamAreNoPeopleWhileAPersonStays) {
  const SceneBox body = person_body(2.0, 10.0, 0.6, 0.5);
  const SceneBox pole = post(-2.0, 6.0, 0.15, 4.0), trunk = post(3.5, 7.5, 0.35, 5.0);
  const Points3 scan = cast_scene({body, head_on(body), pole, trunk});
  const DetectorResult r = detect(scan);
  EXPECT_EQ(people_near(r, body.x, body.z), 1) << describe(r);
  EXPECT_EQ(people_near(r, pole.x, pole.z), 0) << describe(r);
  EXPECT_EQ(people_near(r, trunk.x, trunk.z), 0) << describe(r);
  // the rule that removed them: without it both are people (cut at 1.9-2.0 m by the beam)
  DetectorOptions off;
  off.person_max_head_ratio = 0.0;
  const DetectorResult all = detect(scan, off);
  EXPECT_EQ(people_near(all, pole.x, pole.z), 1) << describe(all);
  EXPECT_EQ(people_near(all, trunk.x, trunk.z), 1) << describe(all);
}
