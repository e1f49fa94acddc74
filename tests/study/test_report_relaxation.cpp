// study/report_relaxation.hpp: the replicas' relaxation histories averaged against t, and the
// report section drawn from them.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "study/report_relaxation.hpp"

using namespace confpack;
using nlohmann::json;

namespace {

// A history of checks at `times` with phi(t) = a + b t and a force ratio 10^(-t).
json linearHistory(const std::vector<double>& times, double a, double b) {
  json h = json::array();
  for (double t : times)
    h.push_back({{"time", t}, {"solid_fraction", a + b * t}, {"Z", 6.0}, {"max_force_ratio", std::pow(10.0, -t)}});
  return h;
}

}  // namespace

TEST_CASE("relaxation: the replicas' mean at each time, linear between checks, a finished run held at its end") {
  const json first = linearHistory({0.0, 1.0, 2.0, 4.0}, 0.60, 0.01);  // checks not evenly spaced
  const json second = linearHistory({0.5, 1.5}, 0.62, 0.0);            // ended at t = 1.5
  const std::vector<double> t = {0.0, 1.0, 3.0, 4.0};
  const std::vector<double> phi = study::meanHistory({first, second}, "solid_fraction", t);
  REQUIRE(phi.size() == 4);
  CHECK(phi[0] == Approx((0.60 + 0.62) / 2));  // before its first check a run has its first value
  CHECK(phi[1] == Approx((0.61 + 0.62) / 2));
  CHECK(phi[2] == Approx((0.63 + 0.62) / 2));  // 3 lies between the checks at 2 and 4
  CHECK(phi[3] == Approx((0.64 + 0.62) / 2));
  // Ratios span decades: their log10 is averaged.
  const std::vector<double> ratio = study::meanHistory({first}, "max_force_ratio", {3.0}, true);
  CHECK(ratio[0] == Approx(-3.0));

  SECTION("the finisher's checks, all at the fall's last time: the last one counts") {
    json h = linearHistory({0.0, 1.0}, 0.60, 0.01);
    h.push_back({{"time", 1.0}, {"solid_fraction", 0.65}});
    CHECK(study::meanHistory({h}, "solid_fraction", {1.0})[0] == Approx(0.65));
  }
  SECTION("checks without the quantity (an older result, a pile with no bulk yet) are skipped") {
    json h = linearHistory({0.0, 1.0}, 0.60, 0.01);
    h[0]["solid_fraction"] = nullptr;
    CHECK(study::meanHistory({h}, "solid_fraction", {0.0})[0] == Approx(0.61));
    CHECK(std::isnan(study::meanHistory({json::array()}, "solid_fraction", {0.0})[0]));
  }
}

TEST_CASE("relaxation section: three figures per family against t, drawn over the latest run's end") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_relaxation_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  study::RelaxationFamily family{"MSP", "relaxation_01", {}};
  family.lines.push_back(
      {"W=5 nscd (n=2)", 1, false, {linearHistory({0.0, 2.0}, 0.6, 0.01), linearHistory({0.0, 8.0}, 0.6, 0.0)}});
  family.lines.push_back({"W=5 bullet (n=1)", 1, true, {linearHistory({0.0, 4.0}, 0.58, 0.0)}});
  const std::vector<double> times = study::relaxationTimes(family, 5);
  REQUIRE(times.size() == 5);
  CHECK(times.back() == 8.0);
  study::Document doc("relaxation");
  study::FigureWriter figures(dir, "");  // data and scripts only
  study::addRelaxationSection(doc, figures, {family});
  CHECK(figures.count() == 3);
  for (const char* q : {"solid_fraction", "Z", "max_force_ratio"})
    CHECK(fs::exists(dir / (std::string("relaxation_01_") + q + ".csv")));
  fs::remove_all(dir);
}
