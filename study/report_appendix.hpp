#pragma once
// The report's closing sections, the record behind its answers: every run once (the missing,
// failed or unequilibrated ones first, each linked to its folder), every quantity of result.json
// per configuration in tables/GROUP.csv at full precision, the cost per side and the method. The
// parts of study/report.cpp share it.
#include <filesystem>

#include "study/report_document.hpp"
#include "study/report_study.hpp"

namespace confpack::study {

// Every run once, the ones missing, failed or not at rest first with why, each name a link to its
// folder in the sweep relative to the report (unless `runLinks` is off).
void addRunsSection(Document& doc, const StudyView& study, const std::filesystem::path& reportDir, bool runLinks);

// Every quantity of result.json per configuration, in tables/FILE.csv (one file per table group),
// and the page's paragraph that lists them.
void addQuantityTables(Document& doc, const StudyView& study, const std::filesystem::path& reportDir);

// What the study cost per backend; each run's wall time is in the run table.
void addCostSection(Document& doc, const StudyView& study);

// The section "Method": the boxes, the builds that computed the runs, where the study is defined, how
// the replicas are averaged and the fits made, what a difference is and the units.
void addMethodSection(Document& doc, const StudyView& study, bool runLinks);

}  // namespace confpack::study
