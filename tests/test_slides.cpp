// The model's slides along itself (model/slides.hpp): found for arcs, coils and straight runs,
// whatever the tube's diameter; none for parts whose shape changes along them.
#include <gtest/gtest.h>

#include <cmath>

#include "model/make_pipe.hpp"
#include "model/pipe_model.hpp"
#include "model/slides.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

std::vector<Slide> slides_of(const PipeModel& m, float arc_mm) {
  return find_slides(SurfaceIndex(m.surface), centreline_of(m.surface, m.tube_diameter_mm),
                     m.tube_diameter_mm, {arc_mm}, 0.25f * m.tube_diameter_mm, 0.6f);
}

TEST(Slides, CentrelineHasThePathsLength) {
  for (const double d : {8.0, 20.0, 40.0}) {
    const PipeModel m = pipe_of("S60,B90r60,S40", d);
    const float length = float(60 + M_PI / 2 * 60 + 40);
    // The caps' samples stretch each end by up to D/2.
    EXPECT_NEAR(centreline_of(m.surface, m.tube_diameter_mm).length_mm(), length, 0.05 * length + d) << d;
  }
}

TEST(Slides, AnArcSlidesAboutItsCentre) {
  for (const double d : {8.0, 12.0, 30.0}) {
    const PipeModel m = pipe_of("B180r100", d);
    const std::vector<Slide> found = slides_of(m, 40);
    ASSERT_EQ(found.size(), 2u) << d;  // both ways
    for (const Slide& s : found) {
      // A turn of 40 / 100 rad about the arc's axis (the bend plane's normal).
      EXPECT_NEAR(rotation_angle_deg(Eigen::Matrix3d::Identity(), s.motion.linear()), 40 / 100.0 * 180 / M_PI,
                  2.0)
          << d;
      EXPECT_GT(s.landing_share, 0.7f) << d;
    }
  }
}

TEST(Slides, AStraightRunSlidesAlongItsAxisAndACoilAlongItsHelix) {
  const PipeModel straight = pipe_of("S200", 20);
  const std::vector<Slide> along = slides_of(straight, 30);
  ASSERT_EQ(along.size(), 2u);
  EXPECT_NEAR(along[0].motion.translation().norm(), 30, 3);
  EXPECT_EQ(slides_of(pipe_of("B120r50,B120r50t15,B120r50t15,B80r50t15", 22), 17).size(), 2u);
}

TEST(Slides, NoneWhereTheShapeChangesAlongThePipe) {
  EXPECT_TRUE(slides_of(pipe_of("S60,B90r30,B-90r30,S60", 12), 30).empty());  // S
  EXPECT_TRUE(slides_of(pipe_of("S40,B90r20,S40", 12), 25).empty());           // elbow
  EXPECT_TRUE(slides_of(pipe_of("S60,B180r40,S60", 12), 30).empty());         // U
  // An arc slid by more than 40 % of its length lands less than 60 % of its surface.
  EXPECT_TRUE(slides_of(pipe_of("B90r100", 20), 80).empty());
}

}  // namespace
}  // namespace pipeloc
