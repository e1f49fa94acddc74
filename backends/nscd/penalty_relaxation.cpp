#include "backends/nscd/penalty_relaxation.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>

#include "core/interrupt.hpp"

namespace confpack::nscd {

using core::Mat3;
using core::Quat;
using core::Vec3;

namespace {

// FIRE's constants (Guenole et al. 2020, table 1): a run of kDelay downhill steps before dt grows.
constexpr int kDelay = 20;
constexpr double kGrow = 1.1, kShrink = 0.5, kAlphaStart = 0.25, kAlphaShrink = 0.99;
// The step in units of sqrt(m / k) of the lightest grain: stable up to about 2 / sqrt(Z) for a
// grain with Z contacts; FIRE halves it after any uphill step, so the largest may be bold.
constexpr double kStepStart = 0.1, kStepMax = 0.5, kStepMin = 0.01;
// The ladder of stiffness rungs: kappa from kFirstStiffness, times kStiffnessFactor, up to the
// last; rungs before the last stop at kRungTolerance (they only bring the next one close).
constexpr double kFirstStiffness = 1e3, kStiffnessFactor = 10.0, kRungTolerance = 1e-2;

Quat rotate(const Quat& q, const Vec3& w, double h) {
  const double angle = w.norm() * h;
  if (angle == 0.0) return q;
  Quat r(Eigen::AngleAxisd(angle, w.normalized()) * q);
  r.normalize();
  return r;
}

}  // namespace

PenaltyRelaxation::PenaltyRelaxation(double finalStiffness, double forceTolerance, long maxIterations)
    : finalStiffness_(finalStiffness), forceTolerance_(forceTolerance), maxIterations_(maxIterations) {
  if (!(finalStiffness > 0.0) || !std::isfinite(finalStiffness))
    throw std::invalid_argument("penalty relaxation: the final stiffness must be a positive number");
  if (!(forceTolerance > 0.0) || !std::isfinite(forceTolerance))
    throw std::invalid_argument("penalty relaxation: the force tolerance must be a positive number");
  if (maxIterations < 1) throw std::invalid_argument("penalty relaxation: max iterations must be at least 1");
}

core::RelaxationOutcome PenaltyRelaxation::run(const core::BoxDef& box, const Vec3& gravity, const RelaxationBodies& bodies,
                                         NarrowPhase& narrow, BroadPhase& broad, int threads,
                                         std::vector<Vec3>& positions, std::vector<Quat>& orientations) {
  core::RelaxationOutcome out;
  const int n = static_cast<int>(positions.size());
  if (n == 0) {
    out.converged = true;
    return out;
  }
  const std::vector<double>& invMass = *bodies.invMass;
  const std::vector<double>& radius = *bodies.radius;
  const std::vector<double>& reach = *bodies.reach;
  const double g = gravity.norm();
  if (!(g > 0.0)) throw std::invalid_argument("penalty relaxation: needs gravity");
  double lightest = std::numeric_limits<double>::infinity(), smallest = lightest, budget = lightest;
  for (int i = 0; i < n; ++i) {
    lightest = std::min(lightest, 1.0 / invMass[i]);
    smallest = std::min(smallest, 2.0 * radius[i]);
    budget = std::min(budget, 0.5 * (reach[i] - radius[i]));  // half the alert band
  }
  // The spheres' diameter; for pinacoids the bounding diameter, a little above L.
  const double unitStiffness = lightest * g / smallest;

  std::vector<Vec3> v(n, Vec3::Zero()), w(n, Vec3::Zero()), force(n), torque(n);
  std::vector<Mat3> invInertia(n);
  std::vector<double> moved(n, 0.0);
  // Tangential springs at the side walls, two per grain (SideLow, SideHigh).
  std::vector<Vec3> spring(2 * static_cast<std::size_t>(n), Vec3::Zero());
  std::vector<char> springActive(2 * static_cast<std::size_t>(n), 0);
  std::vector<CandidatePair> pairs;
  std::vector<ContactGeometry> geometry;
  bool relist = true;

  double kappa = std::min(kFirstStiffness, finalStiffness_);
  for (;;) {
    const bool lastRung = kappa >= finalStiffness_;
    const double k = kappa * unitStiffness;
    const double tolerance = lastRung ? forceTolerance_ : std::max(kRungTolerance, forceTolerance_);
    const double timeUnit = std::sqrt(lightest / k);
    double dt = kStepStart * timeUnit, alpha = kAlphaStart;
    int downhill = 0;
    for (int i = 0; i < n; ++i) v[i] = w[i] = Vec3::Zero();
    bool rungDone = false;
    while (out.iterations < maxIterations_) {
      if (out.iterations % 1024 == 0 && core::stopSignal() != 0)
        throw core::Interrupted(core::stopSignal(),
                                fmt::format("in iteration {} of the penalty relaxation", out.iterations));
      if (relist) {
        broad.findPairs(positions, reach, pairs);
        std::fill(moved.begin(), moved.end(), 0.0);
        relist = false;
      }
      // Forces: gravity, the penalty on every overlapping point, the wall springs.
      for (int i = 0; i < n; ++i) {
        force[i] = gravity / invMass[i];
        torque[i].setZero();
        const Mat3 r = orientations[i].toRotationMatrix();
        invInertia[i] = r * (*bodies.invInertiaBody)[i] * r.transpose();
      }
      narrow.collideAll(pairs, positions, orientations, geometry, threads);
      std::fill(springActive.begin(), springActive.end(), 0);
      double deepest = 0.0;
      for (const ContactGeometry& c : geometry) {
        double normalForce = 0.0;
        Vec3 at = Vec3::Zero();
        for (int p = 0; p < c.pointCount; ++p) {
          if (c.gaps[p] >= 0.0) continue;
          deepest = std::max(deepest, -c.gaps[p]);
          const double f = -k * c.gaps[p];
          const Vec3 fb = f * c.normal;  // on b; a receives -fb
          force[c.a] -= fb;
          torque[c.a] -= (c.points[p] - positions[c.a]).cross(fb);
          if (c.b >= 0) {
            const Vec3 xb = positions[c.b] + Vec3(c.shiftX * box.lengthX, c.shiftY * box.width, 0.0);
            force[c.b] += fb;
            torque[c.b] += (c.points[p] - xb).cross(fb);
          }
          normalForce += f;
          at += f * c.points[p];
        }
        if (c.b >= 0 || normalForce == 0.0) continue;
        const auto wall = static_cast<core::WallId>(c.b);
        const double mu = box.wallFrictionOf(wall);
        if (mu == 0.0) continue;
        // The spring follows the contact point's tangential motion and slides at mu F_n.
        const std::size_t s = 2 * static_cast<std::size_t>(c.a) + (wall == core::WallId::SideLow ? 0 : 1);
        at /= normalForce;
        const Vec3 arm = at - positions[c.a];
        Vec3 slip = v[c.a] + w[c.a].cross(arm);
        slip -= slip.dot(c.normal) * c.normal;
        Vec3& xi = spring[s];
        xi += dt * slip;
        xi -= xi.dot(c.normal) * c.normal;
        Vec3 ft = -k * xi;
        const double cap = mu * normalForce;
        if (ft.norm() > cap) {
          ft *= cap / ft.norm();
          xi = -ft / k;
        }
        springActive[s] = 1;
        force[c.a] += ft;
        torque[c.a] += arm.cross(ft);
      }
      for (std::size_t s = 0; s < spring.size(); ++s)
        if (!springActive[s]) spring[s].setZero();

      double residual = 0.0, power = 0.0;
      for (int i = 0; i < n; ++i) {
        const double weight = g / invMass[i];
        residual = std::max({residual, force[i].norm() / weight, torque[i].norm() / (weight * radius[i])});
        power += force[i].dot(v[i]) + torque[i].dot(w[i]);
      }
      out.residual = residual;
      out.deepestOverlap = deepest;
      if (residual < tolerance) {
        rungDone = true;
        break;
      }
      ++out.iterations;
      // FIRE: uphill, step back half a step, stop and shrink the step; downhill long enough, grow it.
      if (power > 0.0) {
        if (++downhill > kDelay) {
          dt = std::min(dt * kGrow, kStepMax * timeUnit);
          alpha *= kAlphaShrink;
        }
      } else {
        downhill = 0;
        dt = std::max(dt * kShrink, kStepMin * timeUnit);
        alpha = kAlphaStart;
        for (int i = 0; i < n; ++i) {
          positions[i] -= 0.5 * dt * v[i];
          orientations[i] = rotate(orientations[i], w[i], -0.5 * dt);
          v[i] = w[i] = Vec3::Zero();
        }
      }
      // Semi-implicit Euler, then FIRE's mixing of the velocity towards the acceleration (norms
      // with rotations weighted by the bounding radius, so both parts are speeds).
      double speed2 = 0.0, accel2 = 0.0;
      for (int i = 0; i < n; ++i) {
        force[i] *= invMass[i];            // now the acceleration
        torque[i] = invInertia[i] * torque[i];  // now the angular acceleration
        v[i] += dt * force[i];
        w[i] += dt * torque[i];
        const double r2 = radius[i] * radius[i];
        speed2 += v[i].squaredNorm() + r2 * w[i].squaredNorm();
        accel2 += force[i].squaredNorm() + r2 * torque[i].squaredNorm();
      }
      const double mix = accel2 > 0.0 ? alpha * std::sqrt(speed2 / accel2) : 0.0;
      double largest = 0.0;
      for (int i = 0; i < n; ++i) {
        v[i] = (1.0 - alpha) * v[i] + mix * force[i];
        w[i] = (1.0 - alpha) * w[i] + mix * torque[i];
        positions[i] += dt * v[i];
        orientations[i] = rotate(orientations[i], w[i], dt);
        moved[i] += dt * (v[i].norm() + w[i].norm() * radius[i]);
        largest = std::max(largest, moved[i]);
      }
      if (largest > budget) relist = true;
    }
    if (!rungDone) break;
    ++out.rungs;
    if (lastRung) {
      out.converged = true;
      break;
    }
    kappa = std::min(kappa * kStiffnessFactor, finalStiffness_);
  }
  return out;
}

}  // namespace confpack::nscd
