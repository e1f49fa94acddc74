#include "backends/nscd/contact_solver.hpp"

namespace confpack::nscd {

int ContactSolver::solve(std::vector<BodyVelocity>& vel, const NscdSettings& settings, int maxThreads) {
  if (settings.solver == SolverKind::Ipm) {
    const int iterations = ipm_.solve(rows_, *bodies_, vel, settings);
    residual_ = ipm_.residual();
    return iterations;
  }
  if (settings.solver == SolverKind::Mprgp) {
    const int iterations = mprgp_.solve(rows_, vel, settings, maxThreads, bodies_);
    residual_ = mprgp_.residual();
    return iterations;
  }
  const int sweeps = nlgs_.solve(rows_, vel, settings);
  residual_ = nlgs_.residual();
  return sweeps;
}

}  // namespace confpack::nscd
