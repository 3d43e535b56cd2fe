// Physics identities, checked for every algorithm on the PUMA 560 and on
// random chains (revolute only, and mixing prismatic joints): H symmetric positive definite; C qd = h - g
// and C qd = each algorithm's own Coriolis term, with C built from
// the Christoffel symbols of H (exact derivatives by dual numbers); Hdot - 2C
// skew-symmetric; g = dV/dq; energy conserved in torque-free motion.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/dual.hpp"
#include "models/robot/robot_file.hpp"
#include "tests/helpers.hpp"

namespace pumasim {
namespace {

using testing::rel_err;

// The PUMA 560 (six joints, and three with the wrist held at zero, which the
// 3-joint generated kernels serve), revolute random chains, and random chains
// mixing revolute and prismatic joints (n = 3, 6, 12; both conventions).
std::vector<RobotModel> models() {
  return {load_robot("puma560"),
          lock_joints(load_robot("puma560"), 3, Eigen::VectorXd::Zero(6)),
          random_chain(2, 21),
          random_chain(4, 22),
          random_chain(7, 23, DhConvention::kModified),
          random_chain(3, 24, DhConvention::kStandard, "PR"),
          random_chain(6, 25, DhConvention::kModified, "RPP"),
          random_chain(12, 26, DhConvention::kStandard, "RRP"),
          random_chain(12, 27, DhConvention::kModified, "PR")};
}

TEST(Identities, MassMatrixSymmetricPositiveDefinite) {
  for (const RobotModel& m : models()) {
    for (const auto& info : testing::supported(m)) {
      auto b = info.make(m);
      Rng rng(3);
      for (int s = 0; s < 10; ++s) {
        const Eigen::VectorXd q = rng.uniform_vector(m.dof(), -M_PI, M_PI);
        Eigen::MatrixXd H(m.dof(), m.dof());
        b->mass_matrix(q, H);
        EXPECT_LT(rel_err(H, H.transpose()), 1e-14) << info.name << " " << m.name;
        const double min_eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues().minCoeff();
        EXPECT_GT(min_eig, 0.0) << info.name << " " << m.name;
      }
    }
  }
}

// dH/dq_k, exactly, by running the algorithm on dual numbers with tangent e_k.
template <template <class, int> class Algo>
std::vector<Eigen::MatrixXd> mass_matrix_derivatives(const RobotModel& m, const Eigen::VectorXd& q) {
  const int n = m.dof();
  const Chain<Dual, Eigen::Dynamic> chain(m);
  Algo<Dual, Eigen::Dynamic> algo(chain);
  std::vector<Eigen::MatrixXd> dH;
  Eigen::Matrix<Dual, Eigen::Dynamic, 1> qq(n);
  Eigen::Matrix<Dual, Eigen::Dynamic, Eigen::Dynamic> H(n, n);
  for (int k = 0; k < n; ++k) {
    for (int i = 0; i < n; ++i) qq[i] = Dual(q[i], i == k ? 1.0 : 0.0);
    algo.mass_matrix(qq, H);
    dH.push_back(H.unaryExpr([](const Dual& d) { return d.deriv(); }));
  }
  return dH;
}

struct ChristoffelCheck {
  const RobotModel& m;
  template <template <class, int> class Algo>
  void operator()() {
    const int n = m.dof();
    const Chain<double, Eigen::Dynamic> chain(m);
    Algo<double, Eigen::Dynamic> algo(chain);
    Rng rng(17);
    for (int s = 0; s < 5; ++s) {
      const Eigen::VectorXd q = rng.uniform_vector(n, -M_PI, M_PI);
      const Eigen::VectorXd qd = rng.uniform_vector(n, -2, 2);
      const auto dH = mass_matrix_derivatives<Algo>(m, q);
      // C_ij = sum_k 1/2 (dH_ij/dq_k + dH_ik/dq_j - dH_jk/dq_i) qd_k
      Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n), Hdot = Eigen::MatrixXd::Zero(n, n);
      for (int k = 0; k < n; ++k) {
        Hdot += dH[k] * qd[k];
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j)
            C(i, j) += 0.5 * (dH[k](i, j) + dH[j](i, k) - dH[i](j, k)) * qd[k];
      }
      Eigen::VectorXd h(n), g(n), c(n);
      algo.bias(q, qd, h);
      algo.gravity(q, g);
      algo.coriolis(q, qd, c);
      const std::string who = std::string(Algo<double, Eigen::Dynamic>::kName) + " " + m.name;
      EXPECT_LT(rel_err(h - g, C * qd), 1e-10) << who;
      EXPECT_LT(rel_err(c, C * qd), 1e-10) << who << " coriolis";
      const Eigen::MatrixXd N = Hdot - 2 * C;
      EXPECT_LT((N + N.transpose()).norm(), 1e-12 * std::max(Hdot.norm(), 1e-12)) << who;
      // Hdot from one dual pass along qd equals sum_k dH/dq_k qd_k.
      const Chain<Dual, Eigen::Dynamic> dchain(m);
      Algo<Dual, Eigen::Dynamic> dalgo(dchain);
      Eigen::Matrix<Dual, Eigen::Dynamic, 1> qq(n);
      for (int i = 0; i < n; ++i) qq[i] = Dual(q[i], qd[i]);
      Eigen::Matrix<Dual, Eigen::Dynamic, Eigen::Dynamic> Hq(n, n);
      dalgo.mass_matrix(qq, Hq);
      const Eigen::MatrixXd Hdot1 = Hq.unaryExpr([](const Dual& d) { return d.deriv(); });
      EXPECT_LT(rel_err(Hdot, Hdot1), 1e-12) << who;
    }
  }
};

TEST(Identities, CoriolisFromChristoffelSymbolsAndSkewSymmetry) {
  for (const RobotModel& m : models()) testing::for_each_algorithm(m, ChristoffelCheck{m});
}

// g = dV/dq, V from the DH transforms; central differences with step 1e-5 have
// truncation error ~ 1e-10 |V'''|, so 1e-7 relative is a safe, still tight bound.
TEST(Identities, GravityIsTheGradientOfPotentialEnergy) {
  for (const RobotModel& m : models()) {
    const int n = m.dof();
    for (const auto& info : testing::supported(m)) {
      auto b = info.make(m);
      Rng rng(29);
      for (int s = 0; s < 5; ++s) {
        const Eigen::VectorXd q = rng.uniform_vector(n, -M_PI, M_PI);
        Eigen::VectorXd g(n), grad(n);
        b->gravity(q, g);
        const double step = 1e-5;
        for (int k = 0; k < n; ++k) {
          Eigen::VectorXd qp = q, qm = q;
          qp[k] += step;
          qm[k] -= step;
          grad[k] = (potential_energy(m, qp) - potential_energy(m, qm)) / (2 * step);
        }
        EXPECT_LT(rel_err(g, grad, 1e-6), 1e-7) << info.name << " " << m.name;
      }
    }
  }
}

// Torque-free, friction-free motion conserves E = 1/2 qd^T H qd + V(q).
// RK4 at dt = 1e-4 s over 1 s has an energy error of order dt^4 ~ 1e-16 per
// unit time times the solution's derivatives; 1e-8 relative to the energy
// scale is far above that and far below any modelling error (dropping the
// Coriolis term, for instance, breaks it at the 1e-2 level).
TEST(Identities, EnergyIsConservedInTorqueFreeMotion) {
  for (const RobotModel& m : {load_robot("puma560"), random_chain(5, 31),
                              random_chain(5, 32, DhConvention::kStandard, "RP"),
                              random_chain(6, 33, DhConvention::kModified, "PRR")}) {
    for (const auto& info : testing::supported(m)) {
      auto b = info.make(m);
      const int n = m.dof();
      Rng rng(37);
      Eigen::VectorXd q = rng.uniform_vector(n, -1, 1), qd = rng.uniform_vector(n, -1, 1);
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
      Eigen::MatrixXd H(n, n);
      auto energy = [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv) {
        b->mass_matrix(qq, H);
        return 0.5 * vv.dot(H * vv) + potential_energy(m, qq);
      };
      auto accel = [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv) {
        Eigen::VectorXd a(n);
        b->forward_dynamics(qq, vv, zero, a);
        return a;
      };
      const double E0 = energy(q, qd);
      b->mass_matrix(q, H);
      const double scale = 0.5 * qd.dot(H * qd) + std::abs(potential_energy(m, q));
      const double dt = 1e-4;
      double worst = 0;
      for (int step = 0; step < 10000; ++step) {
        const Eigen::VectorXd k1q = qd, k1v = accel(q, qd);
        const Eigen::VectorXd k2q = qd + 0.5 * dt * k1v, k2v = accel(q + 0.5 * dt * k1q, k2q);
        const Eigen::VectorXd k3q = qd + 0.5 * dt * k2v, k3v = accel(q + 0.5 * dt * k2q, k3q);
        const Eigen::VectorXd k4q = qd + dt * k3v, k4v = accel(q + dt * k3q, k4q);
        q += dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
        qd += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
        if (step % 1000 == 999) worst = std::max(worst, std::abs(energy(q, qd) - E0));
      }
      EXPECT_LT(worst / scale, 1e-8) << info.name << " " << m.name;
      EXPECT_GT(qd.norm(), 0.0);
    }
  }
}

}  // namespace
}  // namespace pumasim
