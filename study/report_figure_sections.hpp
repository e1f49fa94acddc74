#pragma once
// The report's figures after the fits (study/report_fits.hpp) and lambda_L: phi and Z against each
// numeric setting the study varies beyond the named axes, the profiles the runs wrote (phi(y),
// Z(y), the fractions of large and small grains, the contact orientations; one section per file,
// averaged over the replicas), and the relaxation histories (study/report_relaxation.hpp). The
// parts of study/report.cpp share it.
#include "study/report_document.hpp"
#include "study/report_figures.hpp"
#include "study/report_study.hpp"

namespace confpack::study {

// For each numeric setting the study varies beyond the named axes (a sweep's setting axis such as
// population.pinacoid.alpha_deg): phi and Z of every configuration against it, one line per
// combination of everything else (family, the other settings, W) and backend. A study in the
// biperiodic box alone has no phi(W) fit: this is where its answers are.
void addSettingSections(Document& doc, const StudyView& study, FigureWriter& figures);

// The profiles the runs wrote, one section per file in the order of profileKinds() and then any
// other, each line a width averaged over its replicas.
void addProfileSections(Document& doc, const StudyView& study, FigureWriter& figures);

// The relaxation histories of the finished runs, per family, configuration and backend
// (study/report_relaxation.hpp).
void addRelaxationSections(Document& doc, const StudyView& study, FigureWriter& figures);

}  // namespace confpack::study
