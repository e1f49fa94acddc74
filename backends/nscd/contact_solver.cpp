#include "backends/nscd/contact_solver.hpp"

#include <algorithm>
#include <cmath>

namespace confpack::nscd {

int ContactSolver::solve(std::vector<BodyVelocity>& vel, const NscdSettings& settings) {
  if (settings.solver == SolverKind::Mprgp) {
    residual_ = 0.0;
    if (rows_.rowCount() == 0) return 0;
    return solveMprgp(rows_, vel, settings);
  }
  const int sweeps = nlgs_.solve(rows_, vel, settings);
  residual_ = nlgs_.residual();
  return sweeps;
}

}  // namespace confpack::nscd
