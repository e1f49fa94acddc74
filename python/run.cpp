// confpack's work functions: deposit, run (deposit, compact, analyse) and analyze, and the default
// configuration. The configuration arrives as the text of config.json (python/confpack/__init__.py
// turns the dict into it) and goes through the same reader and checks as every configuration of
// the command line (core::RunConfig's from_json and validate, the backend's option table), so a
// bad field is refused with the same one-line message.
//
// The long work runs without the GIL. It calls back into Python at its progress points (a
// compaction's equilibrium checks, the deposition's placeholders): there a pending Ctrl-C
// (PyErr_CheckSignals) or an exception of the user's callback unwinds the C++ work, which holds
// nothing that outlives it, and surfaces as that Python exception (KeyboardInterrupt).
#include <fmt/format.h>
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>

#include "analysis/plausibility.hpp"
#include "backends/backend_factory.hpp"
#include "compaction/deposition.hpp"
#include "core/run_config.hpp"
#include "python/bindings.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::python {

namespace {

/// Forwards progress from C++ work that runs without the GIL to an optional Python callable
/// progress(fraction, status), and stops the work when Python has a signal to raise.
class PythonProgress {
 public:
  explicit PythonProgress(py::object callback) : callback_(std::move(callback)) {}
  void operator()(double fraction, const std::string& status) const {
    const py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (!callback_.is_none()) callback_(fraction, status);
  }

 private:
  py::object callback_;
};

core::RunConfig configFromText(const std::string& text, const std::optional<std::string>& backend) {
  core::RunConfig cfg = nlohmann::json::parse(text).get<core::RunConfig>();
  if (backend) cfg.backend = *backend;
  cfg.validate();
  return cfg;
}

/// Column arrays of one profile table.
py::dict layers(const analysis::LayerFractions& l, const char* axis) {
  py::dict d;
  d[axis] = toArray(l.position);
  d["n_large"] = toArray(l.large);
  d["n_small"] = toArray(l.small);
  d["P_L"] = toArray(l.pLarge);
  d["P_S"] = toArray(l.pSmall);
  return d;
}

py::dict histogram(const analysis::Fabric& f, bool cosine) {
  const std::size_t n = cosine ? f.orientation[3].cosTheta.size() : f.orientation[3].azimuth.size();
  const double span = cosine ? 1.0 : 180.0;
  std::vector<double> lo(n), hi(n);
  for (std::size_t k = 0; k < n; ++k) {
    lo[k] = span * k / n;  // the bin edges as writeProfiles writes them
    hi[k] = span * (k + 1) / n;
  }
  py::dict d;
  d[cosine ? "cos_lo" : "azimuth_lo_deg"] = toArray(lo);
  d[cosine ? "cos_hi" : "azimuth_hi_deg"] = toArray(hi);
  const char* names[] = {"simple", "double", "triple", "all"};
  for (int t = 0; t < 4; ++t) {
    std::vector<double> v = cosine ? f.orientation[t].cosTheta : f.orientation[t].azimuth;
    v.resize(n, 0.0);  // a type without contacts has an empty histogram, written as zeros
    d[names[t]] = toArray(v);
  }
  return d;
}

}  // namespace

py::dict profiles(const analysis::Analysis& a) {
  py::dict out;
  py::dict phi;
  phi["y"] = toArray(a.phiProfile.y);
  phi["phi"] = toArray(a.phiProfile.phi);
  out["phi_y"] = phi;
  const analysis::CoordinationProfile& c = a.coordination.profile;
  py::dict z;
  z["y"] = toArray(c.y);
  z["grains"] = toArray(c.grains);
  z["Z"] = toArray(c.z);
  z["simple"] = toArray(c.simple);
  z["double"] = toArray(c.dbl);
  z["triple"] = toArray(c.triple);
  out["z_y"] = z;
  out["homogeneity_z"] = layers(a.homogeneity.alongZ, "z");
  out["homogeneity_y"] = layers(a.homogeneity.alongY, "y");
  out["orientation_cos"] = histogram(a.fabric, true);
  out["orientation_azimuth"] = histogram(a.fabric, false);
  return out;
}

void bindRun(py::module_& m) {
  m.def(
      "_default_config", [] { return nlohmann::json(core::RunConfig{}).dump(); },
      "The default configuration as config.json text.");

  m.def(
      "_resolve_config",
      [](const std::string& text, std::optional<std::string> backend) {
        return nlohmann::json(configFromText(text, backend)).dump();
      },
      "config_text"_a, "backend"_a = py::none(), "The fully resolved configuration (config.json text).");

  m.def(
      "_deposit",
      [](const std::string& text, py::object progress) {
        const core::RunConfig cfg = configFromText(text, std::nullopt);
        const PythonProgress report(std::move(progress));
        PyPacking out;
        {
          const py::gil_scoped_release release;
          const compaction::Deposit pile = compaction::deposit(
              cfg.box, cfg.population, cfg.deposition, cfg.seed, [&](std::size_t done, std::size_t total) {
                report(total ? static_cast<double>(done) / static_cast<double>(total) : 0.0,
                       fmt::format("{}/{} placeholders", done, total));
              });
          out.packing.box = cfg.box;
          out.packing.walls = cfg.walls;
          out.packing.grains = pile.grains;
        }
        return out;
      },
      "config_text"_a, "progress"_a = py::none());

  m.def(
      "_run",
      [](const std::string& text, std::optional<std::string> backend, py::object progress) {
        const core::RunConfig cfg = configFromText(text, backend);
        // As `confpack run`: an unknown option key is refused before any work.
        backends::checkBackendOptions(cfg.backend, cfg.backendOptions);
        const PythonProgress report(std::move(progress));
        std::optional<study::FinishedRun> run;
        {
          const py::gil_scoped_release release;
          run = study::runProtocol(cfg, {},
                                   [&](double fraction, const std::string& status) { report(fraction, status); });
        }
        return py::make_tuple(run->result.dump(), profiles(run->measured), PyPacking{std::move(run->packing), {}});
      },
      "config_text"_a, "backend"_a = py::none(), "progress"_a = py::none());

  const analysis::AnalysisOptions defaults;
  m.def(
      "_analyze",
      [](const PyPacking& p, bool allowImplausible, double margin, double surfaceCell, double slice, double latticeCell,
         bool lattice, double forceThreshold, double gapTolerance, double inflate, double typeBand) {
        analysis::AnalysisOptions options;  // those of `confpack analyze`, with its flags
        options.region.margin = margin;
        options.region.cellSize = surfaceCell;
        options.profile.slice = slice;
        options.interpenetration.cell = latticeCell;
        options.interpenetration.lattice = lattice;
        options.coordination.forceThreshold = forceThreshold;
        options.geometricContacts.absTolerance = gapTolerance;
        options.inflate = inflate;
        options.typeBand = typeBand;
        options.validate();
        analysis::checkPlausible(p.packing, p.source.empty() ? "packing" : p.source, allowImplausible);
        std::optional<analysis::Analysis> a;
        {
          const py::gil_scoped_release release;
          a = analysis::analyze(p.packing, options);
        }
        return py::make_tuple(analysis::toJson(*a).dump(), profiles(*a));
      },
      "packing"_a, "allow_implausible"_a = false, "margin"_a = defaults.region.margin,
      "surface_cell"_a = defaults.region.cellSize, "slice"_a = defaults.profile.slice,
      "lattice_cell"_a = defaults.interpenetration.cell, "lattice"_a = defaults.interpenetration.lattice,
      "force_threshold"_a = defaults.coordination.forceThreshold,
      "gap_tolerance"_a = defaults.geometricContacts.absTolerance, "inflate"_a = defaults.inflate,
      "type_band"_a = defaults.typeBand);
}

}  // namespace confpack::python
