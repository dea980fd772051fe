#pragma once
/// @file ThicknessReport.h
/// @brief The soft-tissue thickness review as a printed document (thesis
/// §2.1, §4.2, §4.3, §5.2): who was scanned, the landmark table with the
/// depth at each landmark by its published convention, the thickness maps
/// unwrapped and painted on the face with the landmarks numbered, the face's
/// thickness statistics, and how everything was measured.

#include <string>

#include "modules/core/Module.h"
#include "modules/report/ReportDocument.h"

namespace caps {
class Scene;
}

namespace caps::report {

struct ThicknessReportOptions
{
  /// Leave out the patient's name, ID, birth date and the folders the data
  /// came from (the PDF's metadata too).
  bool deidentify = false;
  PaperSize paper = PaperSize::A4;
  std::string reviewer; ///< printed in the header; empty: a blank line to sign
  std::string date;     ///< YYYY-MM-DD; empty: today
  /// Print resolution of the figures (dots per inch at their printed size).
  double figureDpi = 220.0;
};

/// The thickness review of the scene's CT, from its label map and its range
/// maps (the newest skin map and the maps built with it); the landmarks are
/// placed automatically (seg::placeLandmarks), and those not placed are
/// listed with why.
/// @throws std::invalid_argument when the scene has no CT or no range maps,
/// naming what to do.
ReportDocument buildThicknessReport(Scene& scene, const ThicknessReportOptions& options,
                                    const TaskProgress& progress = {});

/// The title printed on every page and in the PDF's metadata.
inline constexpr const char* kThicknessReportTitle = "CAPS soft-tissue thickness report";

} // namespace caps::report
