// `confpack analyze FILE --out DIR`: every measurement of docs/model.md on a packing file
// (docs/packing-format.md), whoever made it.
//
//   DIR/result.json   the analysis blocks (docs/model.md, "Results"; equilibrium with zero velocities when the
//                     file carries contact forces, else null), the source file and the options
//   DIR/*.csv         phi_y, z_y, homogeneity_z, homogeneity_y, orientation_cos, orientation_azimuth
//
// The file is read, validated, checked for plausibility (analysis/plausibility.hpp; unless
// --allow-implausible) and analysed before anything is written: a bad file gives one line on
// stderr, exit code 2 and no output directory. SIGINT or SIGTERM stops the analysis at its next
// grain, slice, fit iteration, cell or pair (analysis polls core::stopSignal()): one line saying
// where, exit 130 or 143, nothing written.
// --inflate S and --type-band B ask for the published readings beside the exact one, the default
// (analysis/analyze.hpp); result.json records both in analysis_options and the inflation as `inflate`.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <memory>

#include "analysis/analyze.hpp"
#include "analysis/plausibility.hpp"
#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "core/build_info.hpp"
#include "core/packing_io.hpp"

namespace confpack::app {

namespace {

struct AnalyzeState {
  std::filesystem::path file;
  std::filesystem::path out;
  bool quiet = false;
  bool noLattice = false;
  bool allowImplausible = false;
  analysis::AnalysisOptions options;
};

nlohmann::json optionsJson(const analysis::AnalysisOptions& o) {
  return {{"free_surface_cell", o.region.cellSize},
          {"bulk_margin", o.region.margin},
          {"profile_slice", o.profile.slice},
          {"lattice_cell", o.interpenetration.cell},
          {"lattice", o.interpenetration.lattice},
          {"force_threshold", o.coordination.forceThreshold},
          {"z_profile_slice", o.coordination.slice},
          {"gap_tolerance_abs", o.geometricContacts.absTolerance},
          {"gap_tolerance_rel", o.geometricContacts.relTolerance},
          {"nematic_boundary_distance", o.boundaryDistance},
          {"size_threshold", o.homogeneity.sizeThreshold},
          {"max_cells", o.maxCells},
          {"inflate", o.inflate},
          {"type_band", o.typeBand > 0.0 ? nlohmann::json(o.typeBand) : nlohmann::json(nullptr)}};
}

void runAnalyze(AnalyzeState& st) {
  st.options.interpenetration.lattice = !st.noLattice;
  core::Packing packing;
  analysis::Analysis result;
  checkInput("analyze", [&] {
    st.options.validate();
    checkOutputTarget(st.out);
    WorkStep step("reading the packing file");
    packing = core::readPacking(st.file);
    step.next("checking the packing's plausibility");
    analysis::checkPlausible(packing, st.file, st.allowImplausible);
    // Analysed before any output exists: an inconsistent packing is refused as bad input.
    step.next("analysing the packing");
    result = analysis::analyze(packing, st.options);
  });
  runWork("analyze", [&] {
    StagedOutput output(st.out);
    const WorkStep step("writing the results");
    nlohmann::json j = analysis::toJson(result);
    j["source"] = std::filesystem::absolute(st.file).string();
    j["backend"] = nullptr;
    j["seed"] = nullptr;
    j["version"] = core::version();
    j["revision"] = core::sourceRevision();
    j["analysis_options"] = optionsJson(st.options);
    const nlohmann::json metadata = {{"source", st.file.string()},
                                     {"seed", nullptr},
                                     {"backend", nullptr},
                                     {"version", core::version()},
                                     {"revision", core::sourceRevision()}};
    analysis::writeProfiles(output.dir(), result, metadata);
    writeJson(output.dir() / "result.json", j);
    output.commit();
    if (!st.quiet) {
      const auto& phi = j["solid_fraction"];
      const auto& z = j["coordination"]["Z"];
      // The network's self-stresses and mechanisms, where defined (docs/model.md, "Isostaticity").
      const std::string rigidity = result.rigidity
                                       ? fmt::format(", {} self-stresses, {} mechanisms",
                                                     result.rigidity->selfStresses(), result.rigidity->mechanisms())
                                       : "";
      fmt::print("analyze: {} grains{}, phi = {}, Z = {}{}{} -> {}\n", result.grains,
                 result.inflate != 1.0 ? fmt::format(" inflated by {:g}", result.inflate) : "",
                 phi.is_number() ? fmt::format("{:.5f}", phi.get<double>()) : "n/a",
                 z.is_number() ? fmt::format("{:.3f}", z.get<double>()) : "n/a", rigidity,
                 result.geometricContacts ? " (geometric contacts)" : "", output.target().string());
    }
  });
}

}  // namespace

void registerAnalyze(CLI::App& app) {
  auto st = std::make_shared<AnalyzeState>();
  auto* sub = app.add_subcommand("analyze",
                                 "Analyse a packing file (docs/packing-format.md): writes DIR/result.json and CSV "
                                 "profiles");
  sub->add_option("file", st->file, "Packing file (confpack-packing JSON)")->required();
  sub->add_option("--out", st->out, "Output directory (created; written all or nothing)")->required();
  sub->add_flag("--quiet,-q", st->quiet, "No summary line");
  addAllowImplausibleFlag(*sub, st->allowImplausible);
  auto& o = st->options;
  sub->add_option("--margin", o.region.margin, "Bulk region: clearance from the floor and the free surface [d_L]")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  sub->add_option("--surface-cell", o.region.cellSize, "Free surface: side of the horizontal grid cells [d_L]")
      ->capture_default_str()
      ->check(positiveNumber());
  sub->add_option("--slice", o.profile.slice, "phi(y) slice thickness [d_L]")
      ->capture_default_str()
      ->check(positiveNumber());
  sub->add_option("--lattice-cell", o.interpenetration.cell, "Interpenetration lattice cell side [d_L]")
      ->capture_default_str()
      ->check(positiveNumber());
  sub->add_flag("--no-lattice", st->noLattice, "Skip the lattice bounds of the interpenetration");
  sub->add_option("--max-cells", o.maxCells,
                  "Refuse an analysis whose profiles or grids take more cells than this (a guard against a slice "
                  "or cell typed far too small)")
      ->capture_default_str()
      ->check(realIn(1.0, HUGE_VAL, false, true, "a number >= 1", "CELLS"));
  sub->add_option("--force-threshold", o.coordination.forceThreshold,
                  "Force-carrying contact: f_n above this fraction of the mean f_n")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  sub->add_option("--gap-tolerance", o.geometricContacts.absTolerance,
                  "Geometric contacts (files without contacts): absolute gap tolerance [d_L]")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  // The two published readings beside the exact one (docs/model.md, "Two readings of a packing").
  sub->add_option("--inflate", o.inflate,
                  "Analyse the packing with every grain scaled by S about its centroid (phi, interpenetration, "
                  "contacts and their types of the inflated grains)")
      ->capture_default_str()
      ->check(realIn(1.0, analysis::kMaxInflation, false, false,
                     fmt::format("a factor in [1, {}]", analysis::kMaxInflation), "S"));
  sub->add_option("--type-band", o.typeBand,
                  "Also read the contact types by a tolerance band of B x the grain size (coordination_band)")
      ->check(realIn(0.0, analysis::kMaxTypeBand, true, false,
                     fmt::format("a fraction in (0, {}]", analysis::kMaxTypeBand), "B"));
  sub->callback([st] { runAnalyze(*st); });
}

}  // namespace confpack::app
