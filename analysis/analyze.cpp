#include "analysis/analyze.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/packing_io.hpp"

namespace confpack::analysis {

void AnalysisOptions::validate() const {
  region.validate();
  profile.validate();
  interpenetration.validate();
  coordination.validate();
  geometricContacts.validate();
  fabric.validate();
  homogeneity.validate();
  profileFit.validate();
  if (!(boundaryDistance >= 0.0) || !std::isfinite(boundaryDistance))
    throw std::invalid_argument(fmt::format("analysis: boundary_distance must be >= 0 (got {})", boundaryDistance));
  if (!(maxCells >= 1.0))
    throw std::invalid_argument(fmt::format("analysis: max_cells must be >= 1 (got {})", maxCells));
  if (!(density > 0.0) || !std::isfinite(density))
    throw std::invalid_argument(fmt::format("analysis: density must be positive (got {})", density));
  checkInflation(inflate);
  if (typeBand != 0.0) checkTypeBand(typeBand);  // 0: off
}

double estimatedCells(const core::BoxDef& box, double grains, const AnalysisOptions& options, std::string* what) {
  const double surface =
      std::ceil(box.lengthX / options.region.cellSize) * std::ceil(box.width / options.region.cellSize);
  // phi(y) takes every grain's slab volumes over every slice (solidFractionProfile).
  const std::pair<double, std::string> counts[] = {
      {std::max(grains, 1.0) * std::ceil(box.width / options.profile.slice),
       fmt::format("{:.0f} grains x phi(y) slices of {:g} d_L", grains, options.profile.slice)},
      {std::ceil(box.width / options.coordination.slice),
       fmt::format("Z(y) slices of {:g} d_L", options.coordination.slice)},
      {surface, fmt::format("free-surface cells of {:g} d_L", options.region.cellSize)}};
  const auto* most = &counts[0];
  for (const auto& c : counts)
    if (c.first > most->first) most = &c;
  if (what) *what = most->second;
  return most->first;
}

double estimatedCells(const core::Packing& packing, const AnalysisOptions& options, std::string* what) {
  return estimatedCells(packing.box, static_cast<double>(packing.grains.size()), options, what);
}

void checkCells(const core::BoxDef& box, double grains, const AnalysisOptions& options, std::string_view remedy) {
  std::string what;
  const double cells = estimatedCells(box, grains, options, &what);
  if (!(cells <= options.maxCells))
    throw std::invalid_argument(fmt::format("analysis: about {:.3g} cells ({}), more than max_cells ({:g}); {}", cells,
                                            what, options.maxCells, remedy));
}

namespace {

// The equilibrium test with zero velocities, when asked for and the packing carries forces.
std::optional<EquilibriumReport> equilibriumAtRest(const core::Packing& packing, const AnalysisOptions& options) {
  if (!options.equilibrium || !packing.contacts) return std::nullopt;
  return equilibrium(packing, {}, options.gravity, options.density, options.forceRatio, options.momentRatio,
                     options.kineticRatio, options.region);
}

}  // namespace

Analysis analyze(const core::Packing& packing, const AnalysisOptions& options) {
  options.validate();
  checkCells(packing.box, static_cast<double>(packing.grains.size()), options);
  if (options.inflate != 1.0) {
    AnalysisOptions inflated = options;
    inflated.inflate = 1.0;
    inflated.equilibrium = false;
    inflated.homogeneity.sizeThreshold *= options.inflate;
    Analysis a = analyze(inflate(packing, options.inflate), inflated);
    a.inflate = options.inflate;
    a.equilibrium = equilibriumAtRest(packing, options);  // the forces act on the grains as they are
    return a;
  }
  Analysis a;
  a.grains = static_cast<int>(packing.grains.size());
  bool large = false, small = false;
  for (const core::Grain& g : packing.grains) {
    a.meanSize += g.size;
    (g.size > options.homogeneity.sizeThreshold ? large : small) = true;
  }
  if (a.grains > 0) a.meanSize /= a.grains;
  a.bidisperse = large && small;

  a.region = bulkRegion(packing, options.region);
  a.solid = solidFraction(packing, a.region);
  if (options.voronoi) a.voronoi = voronoiSolidFraction(packing, a.region);
  a.phiProfile = solidFractionProfile(packing, a.region, options.profile);
  if (packing.box.periodicY) {
    a.profileFit.reason = "biperiodic box: no wall profile";
  } else if (a.region.empty()) {
    a.profileFit.reason = "no bulk region";
  } else {
    ProfileFitDef def = options.profileFit;
    def.bidisperse = a.bidisperse;
    a.profileFit = fitProfile(a.phiProfile.y, a.phiProfile.phi, def);
    if (a.profileFit.ok) a.profileIntegralC = profileIntegralC(a.phiProfile, a.profileFit.law.phiBulk);
  }
  a.interpenetration = interpenetration(packing, a.region, options.interpenetration);

  a.geometricContacts = !packing.contacts.has_value();
  const std::vector<core::Contact> contacts =
      a.geometricContacts ? geometricContacts(packing, options.geometricContacts) : *packing.contacts;
  const std::vector<CountedContact> counted =
      forceCarryingContacts(packing, contacts, a.geometricContacts, options.coordination.forceThreshold);
  a.coordination = coordination(packing, a.region, counted, a.geometricContacts, options.coordination);
  if (options.typeBand > 0.0) {
    a.typeBand = options.typeBand;
    a.coordinationBand = coordination(packing, a.region, bandTypedContacts(packing, counted, options.typeBand),
                                      a.geometricContacts, options.coordination);
  }
  a.rigidity = contactRigidity(packing, counted);
  a.fabric = fabric(packing, a.region, counted, options.fabric);
  a.nematic = nematic(packing, a.region, options.boundaryDistance);
  a.homogeneity = homogeneity(packing, a.region, options.homogeneity);
  a.equilibrium = equilibriumAtRest(packing, options);
  return a;
}

namespace {
nlohmann::json orNull(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? nlohmann::json(*v) : nlohmann::json(nullptr);
}
nlohmann::json nematicJson(const std::optional<NematicOrder>& n) {
  if (!n) return nullptr;
  static const char* axes[] = {"u", "v", "w"};
  return {{"q00", n->q00},
          {"axis", axes[n->axis]},
          {"director", {n->director.x(), n->director.y(), n->director.z()}},
          {"grains", n->grains}};
}
}  // namespace

nlohmann::json toJson(const Analysis& a) {
  using nlohmann::json;
  json j;
  j["n_grains"] = a.grains;
  j["inflate"] = a.inflate;
  j["mean_size"] = a.meanSize;
  j["bidisperse"] = a.bidisperse;
  j["free_surface"] = a.region.freeSurface;
  j["bulk_region"] = {{"z_low", a.region.zLow},
                      {"z_high", a.region.zHigh},
                      {"free_surface", a.region.freeSurface},
                      {"volume", a.solid.regionVolume},
                      {"grains", a.coordination.bulkGrains}};
  j["solid_fraction"] = a.region.empty() ? json(nullptr) : json(a.solid.phi);
  j["solid_fraction_voronoi"] = a.voronoi ? json(a.voronoi->phi) : json(nullptr);

  const Coordination& c = a.coordination;
  const bool haveBulk = c.bulkGrains > 0;
  auto perGrain = [&](double v) { return haveBulk ? json(v) : json(nullptr); };
  j["coordination"] = {{"Z", perGrain(c.z)},
                       {"simple", perGrain(c.zSimple)},
                       {"double", perGrain(c.zDouble)},
                       {"triple", perGrain(c.zTriple)},
                       {"Z_non_rattler", perGrain(c.zNonRattler)},
                       {"rattler_fraction", perGrain(c.rattlerFraction)},
                       {"wall", perGrain(c.wallZ)},
                       {"wall_contacts", c.wallContacts},
                       {"contacts", c.contacts},
                       {"hyperstaticity", orNull(c.hyperstaticity)},
                       {"geometric_contacts", a.geometricContacts},
                       {"mean_normal_force", c.meanNormalForce}};
  if (a.coordinationBand) {
    // The band's types beside the exact ones; Z and the rattlers are the same contacts'.
    const Coordination& b = *a.coordinationBand;
    j["coordination_band"] = {{"band", a.typeBand},
                              {"Z", perGrain(b.z)},
                              {"simple", perGrain(b.zSimple)},
                              {"double", perGrain(b.zDouble)},
                              {"triple", perGrain(b.zTriple)},
                              {"constraints", perGrain(b.zSimple + 2 * b.zDouble + 3 * b.zTriple)},
                              {"hyperstaticity", orNull(b.hyperstaticity)}};
  } else {
    j["coordination_band"] = nullptr;
  }

  if (a.rigidity)
    j["rigidity"] = {{"contacts", a.rigidity->contacts},
                     {"constraints", a.rigidity->constraints},
                     {"degrees_of_freedom", a.rigidity->degreesOfFreedom},
                     {"rank", a.rigidity->rank},
                     {"self_stresses", a.rigidity->selfStresses()},
                     {"self_stresses_between_grains", a.rigidity->selfStressesBetweenGrains()},
                     {"mechanisms", a.rigidity->mechanisms()}};
  else
    j["rigidity"] = nullptr;

  const Interpenetration& ip = a.interpenetration;
  j["interpenetration_percent"] = {
      // Like solid_fraction: a percentage of the bulk grain volume does not exist without a bulk.
      {"exact", a.region.empty() ? json(nullptr) : json(ip.exactPercent)},
      {"lattice_min", orNull(ip.latticeMinPercent)},
      {"lattice_max", orNull(ip.latticeMaxPercent)},
      {"overlapping_pairs", ip.overlappingPairs},
      {"max_sphere_depth", ip.maxSphereDepth},
      {"lattice_cells", ip.latticeCells},
      {"lattice_skipped", ip.latticeSkipped.empty() ? json(nullptr) : json(ip.latticeSkipped)}};

  const Fabric& f = a.fabric;
  j["anisotropy"] = f.contacts > 0 ? json(f.anisotropy) : json(nullptr);
  j["fabric"] = {{"eigenvalues", {f.eigenvalues(0), f.eigenvalues(1), f.eigenvalues(2)}},
                 {"major_axis", {f.majorAxis.x(), f.majorAxis.y(), f.majorAxis.z()}},
                 {"contacts", f.contacts}};

  j["nematic"] = {{"bulk", a.nematic.bulk ? json(a.nematic.bulk->q00) : json(nullptr)},
                  {"boundary", a.nematic.boundary ? json(a.nematic.boundary->q00) : json(nullptr)},
                  {"bulk_detail", nematicJson(a.nematic.bulk)},
                  {"boundary_detail", nematicJson(a.nematic.boundary)}};

  const ProfileFit& pf = a.profileFit;
  const ProfileLaw& l = pf.law;
  const ProfileLaw& e = pf.error;
  auto value = [&](double v) { return pf.ok ? json(v) : json(nullptr); };
  auto small = [&](double v) { return pf.ok && l.bidisperse ? json(v) : json(nullptr); };
  j["profile_fit"] = {{"ok", pf.ok},
                      {"reason", pf.ok ? json(nullptr) : json(pf.reason)},
                      {"phi_bulk", value(l.phiBulk)},
                      {"phi_bulk_error", value(e.phiBulk)},
                      {"alpha", value(l.alpha)},
                      {"alpha_error", value(e.alpha)},
                      {"beta_L", value(l.beta[0])},
                      {"beta_L_error", value(e.beta[0])},
                      {"gamma_L", value(l.gamma[0])},
                      {"gamma_L_error", value(e.gamma[0])},
                      {"lambda_L", value(l.lambda[0])},
                      {"lambda_L_error", value(e.lambda[0])},
                      {"beta_S", small(l.beta[1])},
                      {"beta_S_error", small(e.beta[1])},
                      {"gamma_S", small(l.gamma[1])},
                      {"gamma_S_error", small(e.gamma[1])},
                      {"lambda_S", pf.lambdaDetermined[1] ? small(l.lambda[1]) : json(nullptr)},
                      {"lambda_S_error", pf.lambdaDetermined[1] ? small(e.lambda[1]) : json(nullptr)},
                      {"lambda_L_over_d_avg", value(a.meanSize > 0 ? l.lambda[0] / a.meanSize : 0.0)},
                      {"rms_residual", value(pf.rms)},
                      {"dof", value(pf.dof)},
                      {"profile_integral_C", orNull(a.profileIntegralC)}};

  if (a.equilibrium) {
    json eq = *a.equilibrium;
    eq["velocities"] = "assumed_zero";
    j["equilibrium"] = eq;
  } else {
    j["equilibrium"] = nullptr;
  }
  return j;
}

nlohmann::json analyzePacking(const core::Packing& packing, const AnalysisOptions& options) {
  return toJson(analyze(packing, options));
}

namespace {

std::string header(const nlohmann::json& metadata, const std::string& what) {
  std::string s = fmt::format("# confpack {}\n", what);
  if (metadata.is_object())
    for (const auto& [key, v] : metadata.items())
      s += fmt::format("# {}: {}\n", key, v.is_string() ? v.get<std::string>() : v.dump());
  return s;
}

void writeHistogram(const std::filesystem::path& path, const nlohmann::json& metadata, const Fabric& f, bool cosine) {
  std::string s = header(metadata, cosine ? "contact-normal density versus |n_z| = cos(theta) (mean 1)"
                                          : "contact-normal density versus azimuth in degrees (mean 1)");
  s += cosine ? "cos_lo,cos_hi,simple,double,triple,all\n" : "azimuth_lo_deg,azimuth_hi_deg,simple,double,triple,all\n";
  const std::size_t n = cosine ? f.orientation[3].cosTheta.size() : f.orientation[3].azimuth.size();
  const double span = cosine ? 1.0 : 180.0;
  for (std::size_t k = 0; k < n; ++k) {
    s += fmt::format("{},{}", span * k / n, span * (k + 1) / n);
    for (int t = 0; t < 4; ++t) {
      const auto& h = cosine ? f.orientation[t].cosTheta : f.orientation[t].azimuth;
      s += fmt::format(",{}", k < h.size() ? h[k] : 0.0);
    }
    s += "\n";
  }
  core::writeFileAtomically(path, s);
}

void writeLayers(const std::filesystem::path& path, const nlohmann::json& metadata, const LayerFractions& l,
                 const char* axis, const char* what) {
  std::string s = header(metadata, what);
  s += fmt::format("{},n_large,n_small,P_L,P_S\n", axis);
  for (std::size_t k = 0; k < l.position.size(); ++k)
    s += fmt::format("{},{},{},{},{}\n", l.position[k], l.large[k], l.small[k], l.pLarge[k], l.pSmall[k]);
  core::writeFileAtomically(path, s);
}

}  // namespace

void writeProfiles(const std::filesystem::path& dir, const Analysis& a, const nlohmann::json& metadata) {
  {
    std::string s = header(metadata, a.phiProfile.folded ? "solid fraction profile phi(y), averaged over the two walls"
                                                         : "solid fraction profile phi(y)");
    s += fmt::format("# slice: {}\n# z_low: {}\n# z_high: {}\ny,phi\n", a.phiProfile.slice, a.region.zLow,
                     a.region.zHigh);
    for (std::size_t k = 0; k < a.phiProfile.y.size(); ++k)
      s += fmt::format("{},{}\n", a.phiProfile.y[k], a.phiProfile.phi[k]);
    core::writeFileAtomically(dir / "phi_y.csv", s);
  }
  {
    const CoordinationProfile& p = a.coordination.profile;
    std::string s = header(metadata, "coordination profile Z(y) of bulk grains, per contact type");
    s += "y,grains,Z,simple,double,triple\n";
    for (std::size_t k = 0; k < p.y.size(); ++k)
      s += fmt::format("{},{},{},{},{},{}\n", p.y[k], p.grains[k], p.z[k], p.simple[k], p.dbl[k], p.triple[k]);
    core::writeFileAtomically(dir / "z_y.csv", s);
  }
  writeLayers(dir / "homogeneity_z.csv", metadata, a.homogeneity.alongZ, "z",
              "fractions of large and small grains per layer along z");
  writeLayers(dir / "homogeneity_y.csv", metadata, a.homogeneity.alongY, "y",
              "fractions of large and small grains per layer along y (bulk region)");
  writeHistogram(dir / "orientation_cos.csv", metadata, a.fabric, true);
  writeHistogram(dir / "orientation_azimuth.csv", metadata, a.fabric, false);
}

}  // namespace confpack::analysis
