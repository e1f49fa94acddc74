#include "backends/nscd/nlgs_solver.hpp"

#include <algorithm>
#include <cmath>
#include <span>

namespace confpack::nscd {

int NlgsSolver::solve(ContactRows& rows, std::vector<BodyVelocity>& vel, const NscdSettings& settings) {
  residual_ = 0.0;
  if (rows.rowCount() == 0) return 0;
  int sweep = 0;
  while (sweep < settings.maxIterations) {
    ++sweep;
    double sumDelta2 = 0.0, sumR2 = 0.0;
    const double omega = settings.relaxation;
    // Hot loop: one frictionless row. The static body has zero inverse mass, so wall rows need no
    // branch; its velocity stays zero.
    auto normalRow = [&](NormalRow& row) {
      BodyVelocity& va = vel[row.a];
      BodyVelocity& vb = vel[row.b];
      const double un = normalVelocity(row, va, vb);
      const double rNew = std::max(0.0, row.r - omega * (un + row.bias) * row.invW);
      const double dr = rNew - row.r;
      row.r = rNew;
      va.v -= (row.invMa * dr) * row.n;
      va.w -= dr * row.iaAxn;
      vb.v += (row.invMb * dr) * row.n;
      vb.w += dr * row.ibBxn;
      sumDelta2 += dr * dr;
      sumR2 += rNew * rNew;
    };
    auto frictionRow = [&](FrictionRow& row) {
      BodyVelocity& va = vel[row.a];
      // Normal part. The wall does not move: u = -(v_a + w_a x l_a).
      const double un = normalVelocity(row, va);
      const double rn = std::max(0.0, row.rn - (un + row.bias) * row.invWnn);
      const double dn = rn - row.rn;
      row.rn = rn;
      va.v -= (row.invMa * dn) * row.n;
      va.w -= dn * row.iaAxn;
      // Tangential part with the updated normal impulse, projected on the Coulomb disc.
      const auto [d1, d2] = updateTangent(row, va);
      sumDelta2 += dn * dn + d1 * d1 + d2 * d2;
      sumR2 += rn * rn + row.rt1 * row.rt1 + row.rt2 * row.rt2;
    };
    // Forward sweeps only, bottom to top (rows sorted by ContactRows::build()): alternating
    // symmetric sweeps needed more sweeps, not fewer (docs/performance.md, "nscd settings: the
    // measurements behind the defaults").
    for (NormalRow& row : rows.normalRows()) normalRow(row);
    for (FrictionRow& row : rows.frictionRows()) frictionRow(row);
    residual_ = sumR2 > 0.0 ? std::sqrt(sumDelta2 / sumR2) : (sumDelta2 > 0.0 ? 1.0 : 0.0);
    if (sweep >= settings.minIterations && residual_ < settings.tolerance) break;
  }
  const std::span<const NormalRow> normalRows = rows.normalRows();
  rows.storeNormalImpulses([&](std::size_t k) { return normalRows[k].r; });
  return sweep;
}

}  // namespace confpack::nscd
