// `confpack deposit`: the geometric deposition (docs/model.md, "Deposition"), written as a packing
// (no contacts), one ParaView frame and the resolved configuration.
//
//   DIR/packing.json   confpack-packing v1, box + grains after substitution
//   DIR/config.json    the fully resolved RunConfig (re-running with it gives the same pile)
//   DIR/vtk/           deposit_grains_000000.vtp + deposit_grains.pvd
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "apps/progress.hpp"
#include "compaction/deposition.hpp"
#include "core/interrupt.hpp"
#include "core/packing_io.hpp"
#include "core/vtk_writer.hpp"

namespace confpack::app {

namespace {

struct DepositState {
  core::RunConfig cfg;
  CommonOptions opts;
};

void runDeposit(const DepositState& st) {
  core::RunConfig cfg = st.cfg;
  checkInput("deposit", [&] {
    cfg.fitLengthToGrainCap();
    cfg.validate();
    cfg.validateDeposit();
    checkOutputTarget(st.opts.out);
  });
  runWork("deposit", [&] {
    applyThreads(cfg.threads);
    // Staged before the work so that an unwritable --out fails at once, not after the deposit.
    StagedOutput output(st.opts.out);
    if (st.opts.verbosity > 0) fmt::print(stderr, "deposit: configuration {}\n", nlohmann::json(cfg).dump());

    Progress progress("deposit", !st.opts.quiet, 5.0);
    WorkStep step("depositing the grains");
    // The progress callback is the deposition's safe point (every hundredth of the placeholders,
    // at most every 1000): SIGINT or SIGTERM stops it there, the staged output is removed on the
    // way out, exit 130 or 143.
    const compaction::Deposit pile = compaction::deposit(
        cfg.box, cfg.population, cfg.deposition, cfg.seed, [&](std::size_t done, std::size_t total) {
          core::stopIfRequested([&] { return fmt::format("while depositing (placeholder {} of {})", done, total); });
          progress.update(total ? static_cast<double>(done) / static_cast<double>(total) : 0.0,
                          fmt::format("{}/{} placeholders", done, total));
        });
    progress.done(fmt::format("{} grains", pile.grains.size()));

    step.next("writing packing.json");
    core::Packing packing;
    packing.box = cfg.box;
    packing.walls = cfg.walls;
    packing.grains = pile.grains;
    core::writePacking(packing, output.dir() / "packing.json");
    step.next("writing config.json");
    writeJson(output.dir() / "config.json", cfg);
    step.next("writing the ParaView frame");
    core::VtkSeries vtk(output.dir() / "vtk", "deposit");
    vtk.addFrame(0.0, packing);
    vtk.finish();
    // A stop asked for while writing still leaves nothing behind.
    core::stopIfRequested([] { return std::string("while writing the deposit"); });
    step.next("moving the output into place");
    output.commit();

    fmt::print("deposit: {} grains, pile height {:.4g} d_L, solid fraction {:.4f}, {:.2f} s -> {}\n",
               pile.grains.size(), pile.pileHeight, pile.solidFraction, pile.seconds, output.target().string());
  });
}

}  // namespace

void registerDeposit(CLI::App& app) {
  auto st = std::make_shared<DepositState>();
  auto* sub = app.add_subcommand(
      "deposit", "Geometric deposition (docs/model.md): writes DIR/packing.json, DIR/config.json and DIR/vtk/");
  addRunConfigOptions(*sub, st->cfg, st->opts);
  sub->callback([st] { runDeposit(*st); });
}

}  // namespace confpack::app
