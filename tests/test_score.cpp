#include <gtest/gtest.h>

#include <algorithm>

#include "model/make_pipe.hpp"
#include "score/mssd.hpp"
#include "score/scorer.hpp"
#include "sim/dataset_writer.hpp"
#include "test_util.hpp"

namespace pipeloc {
namespace {

// One small simulated dataset per pipe kind, shared by the tests of this file.
class ScorerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    for (const char* name : {"sbend", "torus"}) {
      auto& d = data()[name];
      d.dir = std::make_unique<test::TempDir>();
      PipeSpec spec = pipe_preset(name);
      spec.sides = 16;
      d.model = std::make_unique<PipeModel>(derive_pipe_model(make_pipe(spec), name));
      SimulateRequest req;
      req.out_dir = d.dir->path();
      req.images = 2;
      req.seed = 9;
      req.previews = false;
      req.scene.pile.pipes = 10;
      write_simulated_dataset(*d.model, req);
      d.gt = read_scene_gt(scene_dir(req.out_dir, 1) + "/scene_gt.json");
      d.info = read_scene_gt_info(scene_dir(req.out_dir, 1) + "/scene_gt_info.json");
    }
  }
  static void TearDownTestSuite() { data().clear(); }

  struct Data {
    std::unique_ptr<test::TempDir> dir;
    std::unique_ptr<PipeModel> model;
    std::map<int, std::vector<GtPose>> gt;
    std::map<int, std::vector<GtInfo>> info;
  };
  static std::map<std::string, Data>& data() {
    static std::map<std::string, Data> d;
    return d;
  }

  // The ground truth as results, scored by how visible each pipe is.
  static ResultsFile truth_as_results(const Data& d) {
    ResultsFile f;
    for (const auto& [im, poses] : d.gt)
      for (std::size_t i = 0; i < poses.size(); ++i)
        f.rows.push_back({1, im, 1, d.info.at(im)[i].visib_fract, poses[i].model_to_cam, 0.02});
    return f;
  }
  static int most_visible(const Data& d, int im) {
    const auto& info = d.info.at(im);
    int best = 0;
    for (std::size_t i = 0; i < info.size(); ++i)
      if (info[i].visib_fract > info[best].visib_fract) best = int(i);
    return best;
  }
};

TEST_F(ScorerTest, GroundTruthScoresOneEverywhere) {
  const Data& d = data()["sbend"];
  const ScoreReport r = score_results(d.dir->path(), truth_as_results(d));
  EXPECT_GT(r.overall.top_pipes, 0);
  EXPECT_DOUBLE_EQ(r.overall.top_recall(5), 1.0);
  EXPECT_DOUBLE_EQ(r.overall.top_recall(10), 1.0);
  EXPECT_DOUBLE_EQ(r.overall.best_correct(5), 1.0);
  EXPECT_DOUBLE_EQ(r.overall.best_correct(10), 1.0);
  EXPECT_DOUBLE_EQ(r.overall.precision_10(), 1.0);
  EXPECT_NEAR(r.overall.time_median_s(), 0.02, 1e-12);
  EXPECT_EQ(r.malformed_rows, 0);
}

TEST_F(ScorerTest, DisplacedEstimatesLandOnTheRightSideOfEachBound) {
  const Data& d = data()["sbend"];
  // A pure translation by delta moves every vertex by delta: MSSD = delta.
  for (const double delta : {4.0, 7.0, 12.0}) {
    ResultsFile f;
    for (const auto& [im, poses] : d.gt) {
      const int best = most_visible(d, im);
      Pose p = poses[best].model_to_cam;
      p.translation() += Eigen::Vector3d(0.6, 0.0, 0.8) * delta;
      f.rows.push_back({1, im, 1, 1.0, p, 0.01});
    }
    const ScoreReport r = score_results(d.dir->path(), f);
    EXPECT_DOUBLE_EQ(r.overall.best_correct(5), delta < 5 ? 1.0 : 0.0) << delta;
    EXPECT_DOUBLE_EQ(r.overall.best_correct(10), delta < 10 ? 1.0 : 0.0) << delta;
    EXPECT_DOUBLE_EQ(r.overall.precision_10(), delta < 10 ? 1.0 : 0.0) << delta;
  }
}

TEST_F(ScorerTest, MissesListEveryTopPipeNotFoundWithTheNearestEstimate) {
  const Data& d = data()["sbend"];
  // Per image: the most visible pipe 7 mm off (a miss at 5 mm, 7 mm from it), every other
  // top pipe left out (a miss with no estimate near).
  ResultsFile f;
  int top = 0;
  for (const auto& [im, poses] : d.gt) {
    Pose p = poses[most_visible(d, im)].model_to_cam;
    p.translation() += Eigen::Vector3d(0.0, 0.6, 0.8) * 7.0;
    f.rows.push_back({1, im, 1, 1.0, p, 0.01});
    for (const auto& i : d.info.at(im)) top += i.top ? 1 : 0;
  }
  const ScoreReport r = score_results(d.dir->path(), f, {}, nullptr, true);
  ASSERT_EQ(int(r.misses.size()), top);
  int displaced = 0;
  for (const TopMiss& m : r.misses) {
    const bool is_it = m.gt_index == most_visible(d, m.im_id);
    if (is_it) {
      ++displaced;
      EXPECT_NEAR(m.nearest_mm, 7.0, 1e-6);
      EXPECT_EQ(m.nearest_rank, 0);
    } else {
      EXPECT_GT(m.nearest_mm, 7.0);
    }
  }
  EXPECT_EQ(displaced, int(d.gt.size()));
  const std::string csv = format_misses(r);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), top + 1);
  // Unasked, no list.
  EXPECT_TRUE(score_results(d.dir->path(), f).misses.empty());
}

TEST_F(ScorerTest, RotationErrorIsMaxVertexDisplacement) {
  const Data& d = data()["sbend"];
  const Pose truth = d.gt.at(0)[0].model_to_cam;
  Pose est = truth;
  est.linear() = truth.linear() * Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : d.model->mesh.vertices) v.push_back(p.cast<double>());
  double expected = 0;
  for (const auto& p : v) expected = std::max(expected, (est * p - truth * p).norm());
  EXPECT_NEAR(mssd(v, est, truth, {}, 1e9), expected, 1e-9);
}

TEST_F(ScorerTest, SymmetricModelScoresTheFlippedPoseAsCorrect) {
  const Data& d = data()["torus"];
  ASSERT_EQ(d.model->symmetries.size(), 1u);
  ResultsFile f;
  for (const auto& [im, poses] : d.gt)
    f.rows.push_back({1, im, 1, 1.0, poses[most_visible(d, im)].model_to_cam * d.model->symmetries[0], 0.01});
  const ScoreReport r = score_results(d.dir->path(), f);
  EXPECT_DOUBLE_EQ(r.overall.best_correct(5), 1.0);
}

TEST_F(ScorerTest, AsymmetricModelDoesNotScoreTheFlippedPose) {
  const Data& d = data()["sbend"];
  // The half-turn that maps the torus-like pipe onto itself; for the S-bend it does not.
  Pose flip = Pose::Identity();
  flip.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d c = d.model->centroid.cast<double>();
  flip.translation() = c - flip.linear() * c;
  ResultsFile f;
  for (const auto& [im, poses] : d.gt)
    f.rows.push_back({1, im, 1, 1.0, poses[most_visible(d, im)].model_to_cam * flip, 0.01});
  const ScoreReport r = score_results(d.dir->path(), f);
  EXPECT_DOUBLE_EQ(r.overall.best_correct(10), 0.0);
}

TEST_F(ScorerTest, DuplicateEstimatesCountAgainstPrecision) {
  const Data& d = data()["sbend"];
  ResultsFile f;
  const auto& poses = d.gt.at(0);
  const int best = most_visible(d, 0);
  f.rows.push_back({1, 0, 1, 0.9, poses[best].model_to_cam, 0.01});
  f.rows.push_back({1, 0, 1, 0.8, poses[best].model_to_cam, 0.01});
  f.malformed = 2;
  const ScoreReport r = score_results(d.dir->path(), f);
  EXPECT_EQ(r.overall.estimates, 2);
  EXPECT_DOUBLE_EQ(r.overall.precision_10(), 0.5);
  EXPECT_EQ(r.malformed_rows, 2);
  // Image 1 has no estimate: it counts as a miss for best-correct.
  EXPECT_DOUBLE_EQ(r.overall.best_correct(5), 0.5);
}

// What the PLC gets: one pose per image at most (eval-bop --picks), scored against the pipes
// covered at most 15 %.
TEST_F(ScorerTest, PicksCountRateCorrectAndWrongByDistance) {
  const Data& d = data()["sbend"];
  const int im = d.gt.begin()->first;
  const int best = most_visible(d, im);
  ASSERT_LE(d.info.at(im)[best].occ_by_pipes, 0.15);
  int images_with_top = 0;
  for (const auto& [i, info] : d.info)
    images_with_top += std::any_of(info.begin(), info.end(), [](const GtInfo& g) { return g.top; });
  ASSERT_EQ(images_with_top, 2);
  for (const double delta : {4.0, 7.0, 12.0}) {
    ResultsFile picks;  // one image gets a pick, the other none (DONE_NONE)
    Pose p = d.gt.at(im)[best].model_to_cam;
    p.translation() += Eigen::Vector3d(0.0, 0.6, 0.8) * delta;
    picks.rows.push_back({1, im, 1, 1.0, p, 0.01});
    const ScoreReport r = score_results(d.dir->path(), truth_as_results(d), {}, &picks);
    ASSERT_TRUE(r.has_picks);
    EXPECT_EQ(r.overall.pick_images, 2);
    EXPECT_EQ(r.overall.picked_images, 1);
    EXPECT_DOUBLE_EQ(r.overall.pick_rate(), 0.5);
    EXPECT_EQ(r.overall.picks, 1);
    EXPECT_EQ(r.overall.pick_correct_5, delta < 5 ? 1 : 0) << delta;
    EXPECT_EQ(r.overall.wrong_picks, delta > 10 ? 1 : 0) << delta;
    // The other columns are today's: the truth as results still scores one.
    EXPECT_DOUBLE_EQ(r.overall.top_recall(5), 1.0);
  }
}

TEST_F(ScorerTest, PickOfAPipeCoveredMoreThan15PercentIsNotCorrect) {
  const Data& d = data()["sbend"];
  ResultsFile picks;
  for (const auto& [im, info] : d.info) {
    for (std::size_t i = 0; i < info.size(); ++i) {
      // The first pipe covered more than 15 % in each image, picked exactly.
      if (info[i].occ_by_pipes <= 0.15) continue;
      picks.rows.push_back({1, im, 1, 1.0, d.gt.at(im)[i].model_to_cam, 0.01});
      break;
    }
  }
  ASSERT_EQ(picks.rows.size(), 2u);
  const ScoreReport r = score_results(d.dir->path(), ResultsFile{}, {}, &picks);
  EXPECT_EQ(r.overall.picks, 2);
  EXPECT_EQ(r.overall.pick_correct_5, 0);
  EXPECT_EQ(r.overall.wrong_picks, 2);
  EXPECT_DOUBLE_EQ(r.overall.pick_rate(), 1.0);
}

TEST_F(ScorerTest, PickOfASymmetricPipesTwinIsCorrect) {
  const Data& d = data()["torus"];
  ResultsFile picks;
  for (const auto& [im, poses] : d.gt)
    picks.rows.push_back(
        {1, im, 1, 1.0, poses[most_visible(d, im)].model_to_cam * d.model->symmetries[0], 0.01});
  const ScoreReport r = score_results(d.dir->path(), ResultsFile{}, {}, &picks);
  EXPECT_EQ(r.overall.picks, 2);
  EXPECT_DOUBLE_EQ(r.overall.pick_correct_5mm(), 1.0);
  EXPECT_EQ(r.overall.wrong_picks, 0);
}

TEST_F(ScorerTest, PickFiguresAppearInTableAndJsonOnlyWithPicks) {
  const Data& d = data()["sbend"];
  const ScoreReport without = score_results(d.dir->path(), truth_as_results(d));
  EXPECT_EQ(format_report(without).find("pick_rate"), std::string::npos);
  EXPECT_FALSE(report_to_json(without)["overall"].contains("pick_rate"));
  ResultsFile picks;
  const int im = d.gt.begin()->first;
  picks.rows.push_back({1, im, 1, 1.0, d.gt.at(im)[most_visible(d, im)].model_to_cam, 0.01});
  picks.rows.push_back(
      {1, im, 1, 0.5, d.gt.at(im)[most_visible(d, im)].model_to_cam, 0.01});  // a second: extra
  picks.rows.push_back({7, 0, 1, 0.5, Pose::Identity(), 0.01});               // an image not in the targets
  const ScoreReport with = score_results(d.dir->path(), truth_as_results(d), {}, &picks);
  EXPECT_EQ(with.pick_rows_extra, 1);
  EXPECT_EQ(with.pick_rows_outside_targets, 1);
  EXPECT_NE(format_report(with).find("pick_rate"), std::string::npos);
  const Json j = report_to_json(with);
  EXPECT_DOUBLE_EQ(j["overall"]["pick_rate"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["overall"]["pick_correct_5mm"].get<double>(), 1.0);
  EXPECT_EQ(j["overall"]["wrong_picks"].get<int>(), 0);
  EXPECT_EQ(j["per_object"]["1"]["picks"].get<int>(), 1);
}

TEST(TubeTurns, StraightTubeIsTheSameUnderAnyTurnAboutItsAxis) {
  PipeSpec spec;
  spec.diameter_mm = 45;
  spec.segments = parse_centreline("S120");
  const PipeModel tube = derive_pipe_model(make_pipe(spec), "tube");
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : tube.mesh.vertices) v.push_back(p.cast<double>());
  const std::vector<Pose> turns = with_tube_turns(v, tube.symmetries);
  EXPECT_EQ(turns.size(), tube.symmetries.size() + 71 * (1 + tube.symmetries.size()));
  // A pose turned 37 degrees about the tube's axis (through the centroid, along its length).
  Pose truth = Pose::Identity();
  truth.translation() = Eigen::Vector3d(10, -20, 900);
  const Eigen::Vector3d c = tube.centroid.cast<double>();
  Eigen::Vector3d lo = v[0], hi = v[0];
  for (const auto& p : v) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  Eigen::Index longest;
  (hi - lo).maxCoeff(&longest);
  Pose turn = Pose::Identity();
  turn.linear() = Eigen::AngleAxisd(37 * M_PI / 180, Eigen::Vector3d::Unit(longest)).toRotationMatrix();
  turn.translation() = c - turn.linear() * c;
  const Pose est = truth * turn;
  EXPECT_GT(mssd(v, est, truth, tube.symmetries, 1e9), 10.0);  // without the turns: a miss
  EXPECT_LT(mssd(v, est, truth, turns, 1e9), 1.0);
  // A bent pipe gets no turns.
  spec.segments = parse_centreline("S40,B90r60,S40");
  const PipeModel elbow = derive_pipe_model(make_pipe(spec), "elbow");
  std::vector<Eigen::Vector3d> ev;
  for (const auto& p : elbow.mesh.vertices) ev.push_back(p.cast<double>());
  EXPECT_EQ(with_tube_turns(ev, elbow.symmetries).size(), elbow.symmetries.size());
}

}  // namespace
}  // namespace pipeloc
