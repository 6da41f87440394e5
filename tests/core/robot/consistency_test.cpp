// consistency_test.cpp — the consistency report on textbook solids and each classic violation; the projection.
#include "manipid/core/robot/consistency.h"

#include "manipid/core/errors.h"
#include "rigid_bodies.h"
#include "../input_error_expectations.h"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace manipid::robot {
namespace {

using test_support::field_of;

using testing::box_inertia;
using testing::cylinder_inertia;
using testing::place;
using testing::some_rotation;
using testing::sphere_inertia;

bool mentions(const std::vector<std::string>& findings, const std::string& text) {
  return std::any_of(findings.begin(), findings.end(),
                     [&](const std::string& finding) { return finding.find(text) != std::string::npos; });
}

std::string joined(const std::vector<std::string>& findings) {
  std::string text;
  for (const std::string& finding : findings) text += finding + "\n";
  return text;
}

Eigen::Vector3d sorted(Eigen::Vector3d values) {
  std::sort(values.data(), values.data() + 3);
  return values;
}

TEST(Consistency, TextbookSolidsAreConsistentAtTheirCentreAndMoved) {
  struct Solid {
    const char* name;
    double mass;
    Eigen::Matrix3d inertia;
  };
  const Solid solids[] = {{"box", 4.0, box_inertia(4.0, 0.3, 0.1, 0.05)},
                          {"cylinder", 2.5, cylinder_inertia(2.5, 0.04, 0.4)},
                          {"sphere", 7.0, sphere_inertia(7.0, 0.11)}};
  const Eigen::Vector3d offset(0.12, -0.4, 0.25);
  for (const Solid& solid : solids) {
    for (bool moved : {false, true}) {
      const Eigen::Vector3d com = moved ? offset : Eigen::Vector3d::Zero();
      const Eigen::Matrix3d rotation = moved ? some_rotation() : Eigen::Matrix3d::Identity();
      std::vector<std::string> findings;
      const LinkConsistency result =
          check_link(place(solid.mass, solid.inertia, com, rotation), solid.name, &findings);
      EXPECT_TRUE(result.consistent()) << solid.name << "\n" << joined(findings);
      EXPECT_TRUE(findings.empty()) << joined(findings);
      EXPECT_EQ(result.name, solid.name);
      EXPECT_DOUBLE_EQ(result.mass, solid.mass);
      EXPECT_LT((result.centre_of_mass - com).norm(), 1e-15);
      // The principal moments are the textbook ones, wherever the body was put.
      const Eigen::Vector3d expected = sorted(solid.inertia.diagonal());
      EXPECT_LT((result.principal_moments - expected).cwiseAbs().maxCoeff(), 1e-13 * expected.maxCoeff())
          << solid.name << (moved ? " moved" : "");
      EXPECT_LT((result.inertia_about_com - rotation * solid.inertia * rotation.transpose()).norm(),
                1e-13 * solid.inertia.norm());
      const Eigen::Vector3d& m = result.principal_moments;
      EXPECT_NEAR(result.triangle_margin, m[0] + m[1] - m[2], 1e-15);
      EXPECT_GT(result.triangle_margin, 0.0);
      EXPECT_GT(result.pseudo_inertia_eigenvalues[0], 0.0);
    }
  }
}

TEST(Consistency, PseudoInertiaOfABoxAtItsCentreIsItsSecondMoments) {
  // At the centre, in its own axes: J = diag(m a²/12, m b²/12, m c²/12, m) — ∫x² ρ dV for a box.
  const double m = 3.0, a = 0.4, b = 0.2, c = 0.1;
  const Eigen::Matrix4d pseudo = pseudo_inertia(place(m, box_inertia(m, a, b, c), Eigen::Vector3d::Zero()));
  Eigen::Matrix4d expected = Eigen::Vector4d(m * a * a / 12, m * b * b / 12, m * c * c / 12, m).asDiagonal();
  EXPECT_LT((pseudo - expected).cwiseAbs().maxCoeff(), 1e-16);
  const LinkConsistency result = check_link(place(m, box_inertia(m, a, b, c), Eigen::Vector3d::Zero()), "box");
  const Eigen::Vector4d eigenvalues(m * c * c / 12, m * b * b / 12, m * a * a / 12, m);  // ascending
  EXPECT_LT((result.pseudo_inertia_eigenvalues - eigenvalues).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Consistency, PseudoInertiaOfASphereOffItsCentreByHand) {
  // A sphere with its centre at (d, 0, 0): Σ_c = σE with σ = ½tr(I_c) − (2/5)mr² = (1/5) m r².
  // J = [[σ + m d², 0, 0, m d], [0, σ, 0, 0], [0, 0, σ, 0], [m d, 0, 0, m]]: σ twice, and the
  // roots of λ² − (σ + m d² + m)λ + σm = 0 from the x/mass block.
  const double m = 5.0, r = 0.1, d = 0.3;
  const double sigma = m * r * r / 5.0;
  const double trace = sigma + m * d * d + m, det = sigma * m;
  const double root = std::sqrt(trace * trace - 4.0 * det);
  Eigen::Vector4d expected(0.5 * (trace - root), sigma, sigma, 0.5 * (trace + root));
  std::sort(expected.data(), expected.data() + 4);
  const LinkConsistency result = check_link(place(m, sphere_inertia(m, r), Eigen::Vector3d(d, 0.0, 0.0)), "ball");
  EXPECT_LT((result.pseudo_inertia_eigenvalues - expected).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_TRUE(result.consistent());
}

TEST(Consistency, PseudoInertiaOfAMovedBoxKeepsDeterminantAndShiftsTrace) {
  // J = T J_c Tᵀ with T = [[R, c], [0, 1]] (det T = 1): det J = det J_c = m·Π(m a_i²/12), and
  // tr J = tr Σ_c + m‖c‖² + m.
  const double m = 2.0, a = 0.5, b = 0.3, c = 0.2;
  const Eigen::Vector3d com(0.3, 0.1, -0.2);
  const Eigen::Matrix4d pseudo = pseudo_inertia(place(m, box_inertia(m, a, b, c), com, some_rotation()));
  const double det = m * (m * a * a / 12) * (m * b * b / 12) * (m * c * c / 12);
  EXPECT_NEAR(pseudo.determinant(), det, 1e-12 * det);
  EXPECT_NEAR(pseudo.trace(), m * (a * a + b * b + c * c) / 12 + m * com.squaredNorm() + m, 1e-14);
}

TEST(Consistency, TriangleInequalityViolationIsFoundAndNamed) {
  // I_c = diag(3, 1, 1) kg·m²: positive definite, but Ixx > Iyy + Izz — no body has it.
  const Vector10d link = place(2.0, Eigen::Vector3d(3.0, 1.0, 1.0).asDiagonal(), Eigen::Vector3d(0.1, 0.0, 0.0));
  std::vector<std::string> findings;
  const LinkConsistency result = check_link(link, "forearm", &findings);
  EXPECT_TRUE(result.mass_positive);
  EXPECT_TRUE(result.inertia_about_com_positive_definite);
  EXPECT_FALSE(result.triangle_inequalities);
  EXPECT_FALSE(result.pseudo_inertia_positive_definite);
  EXPECT_FALSE(result.consistent());
  EXPECT_NEAR(result.triangle_margin, -1.0, 1e-14);
  EXPECT_LT(result.pseudo_inertia_eigenvalues[0], 0.0);
  ASSERT_EQ(findings.size(), 2u) << joined(findings);
  EXPECT_EQ(findings[0],
            "forearm: the principal moments of inertia about the centre of mass (1, 1, 3 kg·m²) violate the "
            "triangle inequality: the largest exceeds the sum of the other two by 1 kg·m²");
  EXPECT_TRUE(mentions(findings, "forearm: the pseudo-inertia is not positive definite (smallest eigenvalue -"));
}

TEST(Consistency, NegativeMassIsFoundAndNamed) {
  Vector10d link = place(1.5, box_inertia(1.5, 0.2, 0.2, 0.2), Eigen::Vector3d(0.0, 0.0, 0.1));
  link[0] = -1.5;
  std::vector<std::string> findings;
  const LinkConsistency result = check_link(link, "wrist", &findings);
  EXPECT_FALSE(result.mass_positive);
  EXPECT_FALSE(result.pseudo_inertia_positive_definite);
  EXPECT_FALSE(result.consistent());
  EXPECT_TRUE(std::isnan(result.centre_of_mass[0]));  // not evaluated without a positive mass
  EXPECT_TRUE(std::isnan(result.triangle_margin));
  ASSERT_EQ(findings.size(), 2u) << joined(findings);
  EXPECT_EQ(findings[0], "wrist: the mass is not positive (-1.5 kg)");
  EXPECT_TRUE(mentions(findings, "wrist: the pseudo-inertia is not positive definite"));
}

TEST(Consistency, IndefiniteInertiaAboutTheCentreIsFoundEvenWhenTheOriginInertiaIsPositive) {
  // The classic trap: checking I_O. Here I_c = diag(0.1, −0.05, 0.1) kg·m² with 10 kg at
  // 0.5 m along x, so I_O = I_c + diag(0, 2.5, 2.5) is positive definite.
  const Vector10d link = place(10.0, Eigen::Vector3d(0.1, -0.05, 0.1).asDiagonal(), Eigen::Vector3d(0.5, 0.0, 0.0));
  Eigen::Matrix3d origin;
  origin << link[4], link[5], link[6], link[5], link[7], link[8], link[6], link[8], link[9];
  ASSERT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(origin).eigenvalues().minCoeff(), 0.09);

  std::vector<std::string> findings;
  const LinkConsistency result = check_link(link, "link3", &findings);
  EXPECT_TRUE(result.mass_positive);
  EXPECT_FALSE(result.inertia_about_com_positive_definite);
  EXPECT_NEAR(result.principal_moments[0], -0.05, 1e-14);
  EXPECT_FALSE(result.consistent());
  ASSERT_FALSE(findings.empty());
  EXPECT_EQ(findings[0],
            "link3: the inertia about the centre of mass is not positive definite (smallest eigenvalue -0.05 kg·m²)");
  EXPECT_TRUE(mentions(findings, "link3: the pseudo-inertia is not positive definite"));
}

TEST(Consistency, FlatPlateAndPointMassAreOnTheBoundaryNotInside) {
  // A plate with no thickness: I_c = m/12 diag(b², a², a² + b²), the triangle holds with equality.
  const double m = 1.0, a = 0.3, b = 0.2;
  std::vector<std::string> findings;
  const LinkConsistency plate =
      check_link(place(m, Eigen::Vector3d(b * b, a * a, a * a + b * b).asDiagonal() * (m / 12),
                       Eigen::Vector3d(0.1, 0.2, 0.3)),
                 "plate", &findings);
  EXPECT_TRUE(plate.inertia_about_com_positive_definite);
  EXPECT_FALSE(plate.triangle_inequalities);
  EXPECT_FALSE(plate.consistent());
  EXPECT_TRUE(mentions(findings, "plate: the principal moments of inertia about the centre of mass"));
  EXPECT_TRUE(mentions(findings, "meet the triangle inequality only with equality: a body with no thickness"));

  findings.clear();
  const LinkConsistency point = check_link(place(3.0, Eigen::Matrix3d::Zero(), Eigen::Vector3d(0.4, 0.0, 0.0)),
                                           "tool", &findings);
  EXPECT_FALSE(point.inertia_about_com_positive_definite);
  EXPECT_FALSE(point.consistent());
  EXPECT_TRUE(mentions(findings, "tool: the inertia about the centre of mass is not positive definite"));
}

TEST(Consistency, ReportNamesLinksAndNonNegativeParameters) {
  ParameterStructure structure = testing::arm_structure(2);
  structure.link_names = {"upper_arm", "forearm"};
  Eigen::VectorXd pi(structure.parameter_count);
  pi.segment<10>(0) = place(4.0, box_inertia(4.0, 0.4, 0.1, 0.1), Eigen::Vector3d(0.2, 0.0, 0.0));
  pi.segment<10>(10) = place(2.0, Eigen::Vector3d(3.0, 1.0, 1.0).asDiagonal(), Eigen::Vector3d::Zero());
  pi.tail(6) << 0.5, 0.2, -0.1,  // joint 1: fv, fc, fo (fo may be negative)
      0.3, -0.05, 0.1;            // joint 2: fc negative
  const ConsistencyReport report = check_consistency(structure, pi);
  EXPECT_FALSE(report.consistent());
  ASSERT_EQ(report.links.size(), 2u);
  EXPECT_TRUE(report.links[0].consistent());
  EXPECT_FALSE(report.links[1].consistent());
  EXPECT_EQ(report.inconsistent_links(), std::vector<int>{1});
  ASSERT_EQ(report.non_negative.size(), 4u);
  EXPECT_TRUE(report.non_negative[0].ok && report.non_negative[1].ok && report.non_negative[2].ok);
  EXPECT_FALSE(report.non_negative[3].ok);
  EXPECT_EQ(report.non_negative[3].name, "fc2");
  EXPECT_EQ(report.non_negative[3].index, 24);
  EXPECT_TRUE(mentions(report.findings, "forearm: the principal moments"));
  EXPECT_TRUE(mentions(report.findings, "fc2: must not be negative, is -0.05"));
  EXPECT_FALSE(mentions(report.findings, "upper_arm"));
  EXPECT_FALSE(mentions(report.findings, "fo1"));

  pi[24] = 0.05;
  pi.segment<10>(10) = place(2.0, box_inertia(2.0, 0.3, 0.1, 0.1), Eigen::Vector3d::Zero());
  const ConsistencyReport fixed = check_consistency(structure, pi);
  EXPECT_TRUE(fixed.consistent());
  EXPECT_TRUE(fixed.findings.empty()) << joined(fixed.findings);
}

TEST(Consistency, UnusableStructureOrVectorNamesTheField) {
  const ParameterStructure good = testing::arm_structure(2);
  const Eigen::VectorXd pi = Eigen::VectorXd::Ones(good.parameter_count);
  auto check = [&](const ParameterStructure& structure, const Eigen::VectorXd& vector) {
    return field_of([&] { check_consistency(structure, vector); });
  };
  ParameterStructure bad = good;
  bad.link_offsets[1] = 5;  // overlaps link 1
  EXPECT_EQ(check(bad, pi), "structure.link_offsets");
  bad = good;
  bad.link_offsets[1] = good.parameter_count - 9;  // runs past the end
  EXPECT_EQ(check(bad, pi), "structure.link_offsets");
  bad = good;
  bad.non_negative.push_back(3);  // inside link 1
  EXPECT_EQ(check(bad, pi), "structure.non_negative");
  bad = good;
  bad.non_negative.push_back(bad.non_negative.front());
  EXPECT_EQ(check(bad, pi), "structure.non_negative");
  bad = good;
  bad.non_negative.push_back(good.parameter_count);
  EXPECT_EQ(check(bad, pi), "structure.non_negative");
  bad = good;
  bad.link_names.pop_back();
  EXPECT_EQ(check(bad, pi), "structure.link_names");
  bad = good;
  bad.parameter_names.pop_back();
  EXPECT_EQ(check(bad, pi), "structure.parameter_names");
  bad = good;
  bad.parameter_count = 0;
  EXPECT_EQ(check(bad, pi), "structure.parameter_count");

  EXPECT_EQ(check(good, Eigen::VectorXd::Ones(good.parameter_count - 1)), "pi");
  Eigen::VectorXd with_nan = pi;
  with_nan[7] = std::nan("");
  EXPECT_EQ(check(good, with_nan), "pi");
  Vector10d huge = Vector10d::Constant(1e308);
  EXPECT_EQ(field_of([&] { check_link(huge, "big"); }), "big");  // ½tr(I_O) overflows: refused, not eigen-solved
}

TEST(Consistency, PseudoInertiaAndStandardParametersRoundTrip) {
  const Vector10d link = place(3.0, box_inertia(3.0, 0.3, 0.2, 0.1), Eigen::Vector3d(0.1, -0.2, 0.3), some_rotation());
  EXPECT_LT((standard_from_pseudo_inertia(pseudo_inertia(link)) - link).cwiseAbs().maxCoeff(), 1e-15);
}

// ---- Projection ----

// ‖J̃(a) − J̃(b)‖_F with J̃ = D J D, the metric the projection is nearest in.
double scaled_distance(const Vector10d& a, const Vector10d& b, double length) {
  const Eigen::Vector4d d(1.0 / length, 1.0 / length, 1.0 / length, 1.0);
  return (d.asDiagonal() * (pseudo_inertia(a) - pseudo_inertia(b)) * d.asDiagonal()).norm();
}

TEST(Projection, ConsistentLinkIsReturnedUnchanged) {
  const Vector10d link = place(3.0, cylinder_inertia(3.0, 0.05, 0.5), Eigen::Vector3d(0.0, 0.0, 0.25), some_rotation());
  const LinkProjection projection = project_link(link);
  EXPECT_FALSE(projection.changed);
  EXPECT_EQ(projection.distance, 0.0);
  EXPECT_TRUE(projection.link == link);  // bit for bit
  // The length scale is the radius of gyration about the origin: √(tr Σ / m).
  EXPECT_NEAR(projection.length_scale, std::sqrt(0.5 * (link[4] + link[7] + link[9]) / link[0]), 1e-15);
}

TEST(Projection, InconsistentLinkLandsConsistentAndNearest) {
  // A consistent truth, then an estimate of it with I_c made indefinite (as noisy data do).
  const Vector10d truth =
      place(2.0, box_inertia(2.0, 0.4, 0.06, 0.05), Eigen::Vector3d(0.2, 0.01, 0.0), some_rotation());
  Vector10d estimate = truth;
  estimate[4] -= 0.004;   // Ixx
  estimate[8] += 0.0015;  // Iyz
  ASSERT_FALSE(check_link(estimate, "estimate").consistent());

  const double length = 0.25;
  ProjectionOptions options;
  options.length_scale = length;
  const LinkProjection projection = project_link(estimate, options);
  EXPECT_TRUE(projection.changed);
  std::vector<std::string> findings;
  EXPECT_TRUE(check_link(projection.link, "projected", &findings).consistent()) << joined(findings);
  EXPECT_NEAR(projection.distance, scaled_distance(projection.link, estimate, length), 1e-12);

  // Nearest: no consistent link we can think of is closer — the truth, or random consistent ones
  // around the estimate.
  EXPECT_LE(projection.distance, scaled_distance(truth, estimate, length));
  std::mt19937_64 engine(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  int candidates = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vector10d candidate = truth;
    for (int i = 0; i < 10; ++i) candidate[i] += 0.002 * noise(engine) * std::max(std::abs(truth[i]), 0.01);
    if (!check_link(candidate, "candidate").consistent()) continue;
    ++candidates;
    EXPECT_LE(projection.distance, scaled_distance(candidate, estimate, length) * (1 + 1e-12));
  }
  EXPECT_GT(candidates, 100);
  // Close: the change is of the size of the damage done, not of the link.
  EXPECT_LT((projection.link - estimate).cwiseAbs().maxCoeff(), 0.01);

  // Projecting again with the same L changes nothing beyond rounding (the floor is relative to
  // the largest eigenvalue, which clipping leaves alone).
  const LinkProjection again = project_link(projection.link, options);
  EXPECT_LT((again.link - projection.link).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(Projection, FloorKeepsEveryScaledEigenvalueAboveItsShare) {
  Vector10d link = place(1.0, Eigen::Vector3d(3.0, 1.0, 1.0).asDiagonal(), Eigen::Vector3d::Zero());
  link[0] = -0.5;  // negative mass as well
  ProjectionOptions options;
  options.length_scale = 1.0;
  options.relative_floor = 1e-3;
  const LinkProjection projection = project_link(link, options);
  const Eigen::Vector4d values =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(pseudo_inertia(projection.link)).eigenvalues();
  EXPECT_GE(values[0], 1e-3 * values[3] * (1 - 1e-12));
  EXPECT_GT(projection.link[0], 0.0);
  EXPECT_TRUE(check_link(projection.link, "projected").consistent());
}

TEST(Projection, NothingPositiveToKeepIsAnInputError) {
  Vector10d link = Vector10d::Zero();
  link[0] = -1.0;  // J = diag(0, 0, 0, −1)
  EXPECT_EQ(field_of([&] { project_link(link, {}, "link2"); }), "link2");
  ProjectionOptions bad;
  bad.relative_floor = 0.0;
  EXPECT_EQ(field_of([&] { project_link(Vector10d::Ones(), bad); }), "projection.relative_floor");
  bad = {};
  bad.length_scale = -1.0;
  EXPECT_EQ(field_of([&] { project_link(Vector10d::Ones(), bad); }), "projection.length_scale");
}

}  // namespace
}  // namespace manipid::robot
