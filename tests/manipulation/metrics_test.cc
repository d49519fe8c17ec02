#include "inference/manipulation/metrics.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

using testing::ExpectErrorContains;

/// LDJ of a rest-to-rest minimum-jerk movement (closed form, peak-speed normalisation):
/// integral of jerk^2 = 720 A^2 / T^5, v_peak = 1.875 A / T.
const double kMinJerkLdj = -std::log(720.0 / (1.875 * 1.875));

/// Minimum-jerk position profile 10 s^3 - 15 s^4 + 6 s^5 at s in [0, 1].
double MinJerk(double s) { return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s); }

/// `samples` uniform samples over [0, duration] of p0 + direction * amplitude * MinJerk(t / T).
TimedPath MinJerkPath(const Eigen::VectorXd& p0, const Eigen::VectorXd& direction, double amplitude,
                      double duration, int samples) {
  TimedPath path;
  path.dt = duration / (samples - 1);
  path.positions.resize(p0.size(), samples);
  for (int i = 0; i < samples; ++i)
    path.positions.col(i) =
        p0 + direction * amplitude * MinJerk(static_cast<double>(i) / (samples - 1));
  return path;
}

/// `count` equal minimum-jerk sub-movements in sequence (rest between them), 1-D.
TimedPath SubMovements(int count, int samples_per_movement, double amplitude, double duration) {
  TimedPath path;
  const int samples = count * samples_per_movement + 1;
  path.dt = duration / (samples - 1);
  path.positions.resize(1, samples);
  for (int i = 0; i < samples; ++i) {
    const int m = std::min(i / samples_per_movement, count - 1);
    const double s = static_cast<double>(i - m * samples_per_movement) / samples_per_movement;
    path.positions(0, i) = amplitude * (m + MinJerk(s));
  }
  return path;
}

double Ldj(const TimedPath& path) {
  const LdjResult r = LogDimensionlessJerk(path);
  EXPECT_TRUE(r.ok()) << ToString(r.status);
  return r.value.value_or(0.0);
}

TEST(PathLength, SumsSegmentNorms) {
  Eigen::MatrixXd p(2, 3);
  p << 0, 3, 3, 0, 4, 10;
  EXPECT_DOUBLE_EQ(PathLength(p), 5.0 + 6.0);
  EXPECT_EQ(PathLength(Eigen::MatrixXd::Ones(7, 1)), 0.0);
  EXPECT_EQ(PathLength(Eigen::MatrixXd(7, 0)), 0.0);
  p(1, 1) = std::nan("");
  ExpectErrorContains([&] { PathLength(p); }, {"PathLength", "non-finite"});
}

TEST(LogDimensionlessJerk, MinimumJerkMatchesClosedForm) {
  const TimedPath path =
      MinJerkPath(Eigen::VectorXd::Constant(1, 0.3), Eigen::VectorXd::Ones(1), 0.8, 1.5, 151);
  EXPECT_NEAR(Ldj(path), kMinJerkLdj, 1e-3);
  EXPECT_NEAR(kMinJerkLdj, -std::log(204.8), 1e-12);
}

TEST(LogDimensionlessJerk, StraightLineIn3dMatchesClosedForm) {
  const Eigen::Vector3d direction = Eigen::Vector3d(1, -2, 0.5).normalized();
  const TimedPath path = MinJerkPath(Eigen::Vector3d(0.1, 0.2, 0.3), direction, 0.6, 2.0, 201);
  EXPECT_NEAR(Ldj(path), kMinJerkLdj, 1e-3);
}

TEST(LogDimensionlessJerk, ConvergesAtSecondOrder) {
  const auto error = [](int samples) {
    return std::abs(
        Ldj(MinJerkPath(Eigen::VectorXd::Zero(1), Eigen::VectorXd::Ones(1), 1.0, 1.0, samples)) -
        kMinJerkLdj);
  };
  const double coarse = error(201), fine = error(401);
  EXPECT_LT(error(101), 1e-3);  // 100 steps per movement
  EXPECT_GT(coarse / fine, 3.0) << "coarse " << coarse << " fine " << fine;
}

TEST(LogDimensionlessJerk, InvariantToAmplitudeAndDuration) {
  const Eigen::Vector3d p0(0.2, -0.1, 0.4);
  const Eigen::Vector3d direction = Eigen::Vector3d(0.3, 0.4, -0.2).normalized();
  // A path with several sub-movements in different directions (not a closed-form case).
  TimedPath base;
  base.dt = 0.01;
  base.positions.resize(3, 301);
  for (int i = 0; i < 301; ++i) {
    const double t = i * base.dt;
    base.positions.col(i) =
        p0 + direction * MinJerk(t / 3.0) + Eigen::Vector3d(0, 0.2, 0) * std::sin(2.0 * t) * t;
  }
  const double reference = Ldj(base);
  TimedPath scaled = base;
  scaled.positions *= 7.5;
  EXPECT_NEAR(Ldj(scaled), reference, 1e-9);
  TimedPath slow = base;
  slow.dt *= 4.0;
  EXPECT_NEAR(Ldj(slow), reference, 1e-9);
  TimedPath shifted = base;
  shifted.positions.colwise() += Eigen::Vector3d(5, -3, 1);
  EXPECT_NEAR(Ldj(shifted), reference, 1e-9);
  // Different sampling of the same continuous motion agrees to discretisation error.
  EXPECT_NEAR(Ldj(MinJerkPath(p0, direction, 0.5, 1.0, 101)),
              Ldj(MinJerkPath(p0, direction, 2.0, 4.0, 401)), 2e-3);
}

TEST(LogDimensionlessJerk, MoreSubMovementsAreLessSmooth) {
  // n equal minimum-jerk sub-movements: integral of jerk^2 = n^6 720 A^2 / T^5, v_peak = 1.875 n A
  // / T, so LDJ = -ln(204.8 n^4).
  double previous = 0;
  for (int n = 1; n <= 4; ++n) {
    const double ldj = Ldj(SubMovements(n, 100, 0.4, 2.0));
    EXPECT_NEAR(ldj, kMinJerkLdj - 4.0 * std::log(n), 2e-3) << n << " sub-movements";
    if (n > 1) {
      EXPECT_LT(ldj, previous);
    }
    previous = ldj;
  }
}

TEST(LogDimensionlessJerk, DegenerateInputsHaveAStatusNotNan) {
  TimedPath short_path{Eigen::MatrixXd::Random(3, kMinLdjSamples - 1), 0.01};
  LdjResult r = LogDimensionlessJerk(short_path);
  EXPECT_EQ(r.status, LdjStatus::kTooFewSamples);
  EXPECT_FALSE(r.value.has_value());

  TimedPath still{Eigen::MatrixXd::Constant(7, 50, 0.3), 0.01};
  r = LogDimensionlessJerk(still);
  EXPECT_EQ(r.status, LdjStatus::kNoMotion);
  EXPECT_FALSE(r.value.has_value());

  // Constant velocity on exactly representable samples: zero jerk, LDJ would be +inf.
  TimedPath constant_velocity{Eigen::MatrixXd(1, 20), 0.25};
  for (int i = 0; i < 20; ++i) constant_velocity.positions(0, i) = i;
  r = LogDimensionlessJerk(constant_velocity);
  EXPECT_EQ(r.status, LdjStatus::kNonFinite);
  EXPECT_FALSE(r.value.has_value());

  EXPECT_EQ(LdjResult{}.status, LdjStatus::kNotEvaluated);
  EXPECT_STREQ(ToString(LdjStatus::kNoMotion), "no_motion");
}

TEST(LogDimensionlessJerk, BadInputIsAnError) {
  TimedPath path{Eigen::MatrixXd::Random(2, 10), 0.0};
  ExpectErrorContains([&] { LogDimensionlessJerk(path); }, {"dt = 0"});
  path.dt = 0.01;
  path.positions(1, 3) = INFINITY;
  ExpectErrorContains([&] { LogDimensionlessJerk(path); }, {"non-finite", "[2 x 10]"});
}

/// Largest speed of joint j over the samples (central differences).
double PeakJointSpeed(const TimedPath& path, int j) {
  double peak = 0;
  for (Eigen::Index i = 1; i + 1 < path.positions.cols(); ++i)
    peak = std::max(
        peak, std::abs(path.positions(j, i + 1) - path.positions(j, i - 1)) / (2.0 * path.dt));
  return peak;
}

TEST(TimeParameterise, SegmentIsMinimumJerkAtTheVelocityLimit) {
  Eigen::MatrixXd waypoints(kDof, 2);
  waypoints.col(0) = JointVector::Zero();
  waypoints.col(1) << 1.0, -0.5, 0.2, 0.0, 0.3, -0.1, 0.05;
  JointVector vmax = JointVector::Constant(2.0);
  vmax(1) = 0.5;  // joint 1 is the slowest to get there: 1.875 * 0.5 / 0.5 = 1.875 s
  const TimedPath path = TimeParameterise(waypoints, vmax, 0.01);
  EXPECT_EQ(path.dt, 0.01);
  ASSERT_EQ(path.positions.cols(), 188 + 1);  // ceil(1.875 / 0.01) steps
  EXPECT_TRUE(testing::MatricesNear(path.positions.col(0), waypoints.col(0), 0));
  EXPECT_TRUE(testing::MatricesNear(path.positions.col(188), waypoints.col(1), 0));
  for (int j = 0; j < kDof; ++j) EXPECT_LE(PeakJointSpeed(path, j), vmax(j) * (1 + 1e-9)) << j;
  EXPECT_NEAR(PeakJointSpeed(path, 1), 0.5, 0.01);
  EXPECT_NEAR(PathLength(path.positions), PathLength(waypoints), 1e-12);
  EXPECT_NEAR(Ldj(path), kMinJerkLdj, 1e-3);
}

TEST(TimeParameterise, WaypointsAreRestPointsAndSamples) {
  Eigen::MatrixXd waypoints(kDof, 4);
  waypoints.col(0) = JointVector::Zero();
  waypoints.col(1) = JointVector::Constant(0.4);
  waypoints.col(2) = waypoints.col(1);  // repeated waypoint: skipped
  waypoints.col(3) = JointVector::Constant(0.8);
  const JointVector vmax = JointVector::Constant(1.0);
  const TimedPath path = TimeParameterise(waypoints, vmax, 0.01);
  const Eigen::Index n = 75;  // 1.875 * 0.4 / 1.0 = 0.75 s per segment
  ASSERT_EQ(path.positions.cols(), 2 * n + 1);
  EXPECT_TRUE(testing::MatricesNear(path.positions.col(n), waypoints.col(1), 0));
  EXPECT_TRUE(testing::MatricesNear(path.positions.col(2 * n), waypoints.col(3), 0));
  // At rest at the middle waypoint: neighbours are symmetric and very close.
  EXPECT_LT((path.positions.col(n + 1) - path.positions.col(n)).norm(), 1e-4);
  EXPECT_NEAR(PathLength(path.positions), PathLength(waypoints), 1e-12);
  // Two equal sub-movements: -ln(204.8 * 2^4).
  EXPECT_NEAR(Ldj(path), kMinJerkLdj - 4.0 * std::log(2.0), 2e-3);
  EXPECT_NEAR(path.duration(), 1.5, 1e-12);
}

TEST(TimeParameterise, SingleWaypointAndBadInput) {
  const JointVector vmax = JointVector::Constant(1.0);
  const TimedPath single = TimeParameterise(Eigen::MatrixXd::Ones(kDof, 1), vmax, 0.01);
  EXPECT_EQ(single.positions.cols(), 1);
  EXPECT_EQ(single.duration(), 0.0);
  EXPECT_EQ(LogDimensionlessJerk(single).status, LdjStatus::kTooFewSamples);
  ExpectErrorContains([&] { TimeParameterise(Eigen::MatrixXd::Ones(6, 2), vmax, 0.01); },
                      {"[6 x 2]", "expected [7 x K]"});
  ExpectErrorContains([&] { TimeParameterise(Eigen::MatrixXd::Ones(kDof, 2), -vmax, 0.01); },
                      {"max_velocity"});
  ExpectErrorContains([&] { TimeParameterise(Eigen::MatrixXd::Ones(kDof, 2), vmax, 0.0); },
                      {"dt = 0"});
}

/// A planar two-link arm on joints 0 and 1 (links 0.5 m and 0.3 m), lifted by joint 2.
Eigen::Vector3d ToyForwardKinematics(const JointVector& q) {
  return {0.5 * std::cos(q(0)) + 0.3 * std::cos(q(0) + q(1)),
          0.5 * std::sin(q(0)) + 0.3 * std::sin(q(0) + q(1)), 0.1 * q(2)};
}

TEST(EvaluatePath, JointAndEndEffectorMetrics) {
  Eigen::MatrixXd waypoints(kDof, 3);
  waypoints.col(0) = JointVector::Zero();
  waypoints.col(1) << 0.5, 0.2, 0.1, 0, 0, 0, 0;
  waypoints.col(2) << 0.9, -0.3, 0.4, 0.1, 0, 0, 0;
  const TimedPath joints = TimeParameterise(waypoints, JointVector::Constant(1.5), 0.01);
  const PathMetrics m = EvaluatePathWithKinematics(joints, ToyForwardKinematics, 0.25);
  EXPECT_TRUE(m.success);
  EXPECT_EQ(m.time_s, 0.25);
  ASSERT_TRUE(m.cspace_length && m.ee_length && m.duration_s);
  EXPECT_NEAR(*m.cspace_length, PathLength(waypoints), 1e-12);
  EXPECT_NEAR(*m.duration_s, joints.duration(), 1e-12);
  const Eigen::Matrix3Xd ee = EndEffectorPath(joints, ToyForwardKinematics);
  EXPECT_NEAR(*m.ee_length, PathLength(ee), 1e-12);
  // The EE arc is at least the chord between its ends.
  EXPECT_GE(*m.ee_length, (ee.col(ee.cols() - 1) - ee.col(0)).norm());
  ASSERT_TRUE(m.cspace_ldj.ok() && m.ee_ldj.ok());
  EXPECT_LT(*m.cspace_ldj.value, kMinJerkLdj);  // two sub-movements
  EXPECT_LT(*m.ee_ldj.value, 0.0);

  const PathMetrics joint_only = EvaluateJointPath(joints, 0.25);
  EXPECT_FALSE(joint_only.ee_length.has_value());
  EXPECT_EQ(joint_only.ee_ldj.status, LdjStatus::kNotEvaluated);
  EXPECT_EQ(*joint_only.cspace_ldj.value, *m.cspace_ldj.value);

  ExpectErrorContains([&] { EvaluatePath(joints, Eigen::Matrix3Xd::Zero(3, 5), 0.1); },
                      {"5 EE positions for"});
  ExpectErrorContains(
      [&] {
        EvaluateJointPath(TimedPath{Eigen::MatrixXd::Zero(3, 5), 0.01}, 0);
      },
      {"[3 x 5]", "expected [7 x T]"});
  ExpectErrorContains([&] { EvaluateJointPath(joints, -1.0); }, {"generation time -1"});
}

TEST(Summarise, StatisticsOverSuccessesOnly) {
  std::vector<PathMetrics> attempts;
  const auto success = [](double length, double time, std::optional<double> ldj) {
    PathMetrics m;
    m.success = true;
    m.time_s = time;
    m.cspace_length = length;
    m.ee_length = length / 2;
    m.duration_s = 1.0;
    if (ldj) m.cspace_ldj = LdjResult{LdjStatus::kOk, ldj};
    m.ee_ldj.status = LdjStatus::kNoMotion;
    return m;
  };
  attempts.push_back(success(2.0, 0.1, -6.0));
  attempts.push_back(PathMetrics::Failure(7.0));
  attempts.push_back(success(4.0, 0.3, -8.0));
  attempts.push_back(success(6.0, 0.2, std::nullopt));
  const MetricSummary s = Summarise(attempts);
  EXPECT_EQ(s.problems, 4);
  EXPECT_EQ(s.successes, 3);
  EXPECT_DOUBLE_EQ(s.success_rate, 0.75);
  EXPECT_EQ(s.cspace_length.n, 3);
  EXPECT_DOUBLE_EQ(*s.cspace_length.mean, 4.0);
  EXPECT_DOUBLE_EQ(*s.cspace_length.std, 2.0);  // sample std: sqrt((4 + 0 + 4) / 2)
  EXPECT_DOUBLE_EQ(*s.ee_length.mean, 2.0);
  EXPECT_NEAR(*s.time_s.mean, 0.2, 1e-15);  // the failure's 7 s is not included
  EXPECT_EQ(s.cspace_ldj.n, 2);             // undefined LDJ left out, not averaged as NaN
  EXPECT_DOUBLE_EQ(*s.cspace_ldj.mean, -7.0);
  EXPECT_DOUBLE_EQ(*s.cspace_ldj.std, std::sqrt(2.0));
  EXPECT_EQ(s.ee_ldj.n, 0);
  EXPECT_FALSE(s.ee_ldj.mean.has_value());

  const std::string json = s.ToJson();
  EXPECT_NE(json.find("\"successes\": 3"), std::string::npos) << json;
  EXPECT_NE(json.find("\"ee_ldj\": {\"mean\": null, \"std\": null, \"n\": 0}"), std::string::npos)
      << json;
  EXPECT_NE(json.find("\"cspace_length\": {\"mean\": 4, \"std\": 2, \"n\": 3}"), std::string::npos)
      << json;
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
  const std::string brief = s.BriefReport();
  EXPECT_NE(brief.find("3/4 solved (75.0%)"), std::string::npos) << brief;
  EXPECT_EQ(brief.find('\n'), std::string::npos);
}

TEST(Summarise, EmptyAndSingleValue) {
  const MetricSummary empty = Summarise({});
  EXPECT_EQ(empty.problems, 0);
  EXPECT_EQ(empty.success_rate, 0.0);
  EXPECT_FALSE(empty.time_s.mean.has_value());
  const Stat one = ComputeStat({3.5});
  EXPECT_EQ(one.n, 1);
  EXPECT_EQ(*one.mean, 3.5);
  EXPECT_FALSE(one.std.has_value());
  ExpectErrorContains([] { ComputeStat({1.0, std::nan("")}); }, {"non-finite"});
}

}  // namespace
}  // namespace foresight::manipulation
