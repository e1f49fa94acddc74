#pragma once
// The report's verdict: the two sides (nscd against Bullet, or the two values of --compare's
// setting) on every family and number of the summary (study/report_summary.hpp), each difference
// with its combined standard error and whether it is larger than twice that error; with a sweep's
// settle_with, the same against the second backend's piles brought to rest, which says what each
// difference is made of; and per family the sentences of its runs (equilibrium, rigidity, failed
// and missing runs). The parts of study/report.cpp share it.
#include "study/report_document.hpp"
#include "study/report_study.hpp"
#include "study/report_summary.hpp"

namespace confpack::study {

// The section "Cross-solver verdict" (or "Verdict: A against B" of --compare's two values).
void addVerdictSection(Document& doc, const StudyView& study, const StudySummary& summary);

}  // namespace confpack::study
