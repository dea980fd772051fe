#pragma once
/// @file PlanReport.h
/// @brief The plan report (thesis §2.1 why a plan is documented,
/// §3.3.3 documentation and storyboards, §5.6 assumptions made explicit):
/// what it says about the patient and about each plan of a scene, computed
/// by the plan logic, and the document built from it.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "modules/core/Module.h"
#include "planning/ConvergenceStudy.h"
#include "planning/PlanRecipe.h"
#include "planning/PlanSimulation.h"
#include "planning/SkinMeasurements.h"
#include "planning/WoundStress.h"
#include "modules/report/ReportDocument.h"

namespace caps {
class Scene;
class PlanNode;
class VolumeNode;
} // namespace caps

namespace caps::report {

/// Options of the report.
struct ReportOptions
{
  /// Leave out everything that names the patient: name, ID, birth date,
  /// the folders the data came from; the PDF's metadata too.
  bool deidentify = false;
  PaperSize paper = PaperSize::A4;
  std::string surgeon;      ///< printed in the header block; empty: a blank line to sign
  std::string planningDate; ///< YYYY-MM-DD; empty: today
  /// The plans to report, by name; empty: every plan of the scene.
  std::vector<std::string> plans;
  /// Print resolution of the figures (dots per inch at their printed size).
  double figureDpi = 220.0;
  /// Solve each plan again with the mesh refined, with 2–4 tissue layers
  /// and with the meshed region grown (rim free and clamped), and table how
  /// the numbers move in an appendix (planning::studyConvergence(); thesis
  /// §5.5). Twelve solves per plan: minutes, not seconds.
  bool convergenceStudy = false;
};

/// Who and what was scanned, as the CT's DICOM fields say.
struct PatientFacts
{
  std::string name, id, birthDate, sex, age;
  std::string studyDate, studyDescription, seriesDescription, modality;
  std::string source; ///< where the CT was read from; empty when de-identified
  bool deidentified = false;
};

/// The CT's fields in print form (DICOM dates as YYYY-MM-DD, person names
/// "FAMILY, Given"); with @a deidentify, name, ID and birth date are
/// replaced by "(de-identified)" and the source left out.
PatientFacts patientFacts(const VolumeNode& volume, bool deidentify);
/// The line printed at the top of every page.
std::string patientLine(const PatientFacts& patient);

/// What the report says about one plan: the plan rebuilt from the scene and
/// predicted again from its recipe (the same mesh and solve as when it was
/// made, bit for bit), and the measurements.
struct PlanFacts
{
  std::string name;           ///< the Plan node's name
  std::string procedureTitle; ///< "Z-plasty"
  std::string reference;      ///< where the procedure is described
  /// Parameter label, value and unit, in the procedure file's units.
  std::vector<std::array<std::string, 3>> parameters;
  planning::IncisionPlan plan;
  std::optional<planning::PlanRecipe> recipe;
  planning::SimulationOptions options;
  planning::PlanMeasurements measured;
  planning::PlanPrediction prediction;
  planning::WoundStress woundStress;
  /// The linear preview of the same plan on the same mesh, beside a
  /// large-deformation prediction: how far it puts the skin from the
  /// prediction and its own check; unset for a linear prediction.
  struct Preview
  {
    planning::SkinDifference difference;
    planning::PredictionCheck check;
    double tensionPerCentimetre = 0.0;
  };
  std::optional<Preview> preview;
  /// How the numbers depend on the model's own choices; set when the report
  /// asks for it (ReportOptions::convergenceStudy).
  std::optional<planning::ConvergenceStudy> convergence;
  double woundStressTheta = 0.0, woundStressZ = 0.0; ///< where the peak is (radians, mm)
  double excisedVolumeToBone = 0.0;                  ///< by the range maps (mm³), the second method
  /// Soft-tissue thickness under the cut path (mm), sampled every 0.5 mm
  /// along it on the thickness map; NaN when the scene has none.
  double thicknessMin = 0.0, thicknessMean = 0.0, thicknessMax = 0.0;
  std::string ctSha256;  ///< of the CT the plan was made on (its recipe)
  std::string skinMapId; ///< the RangeMap node the plan was drawn on (RangeMapLogic::mapsOf)
};

/// The facts of @a plan in @a scene (its skin, bone and thickness maps).
/// @throws std::invalid_argument naming what is missing (no range maps, a
/// plan that does not fit its map), std::runtime_error from the solve.
/// With @a studyConvergence, PlanFacts::convergence too.
PlanFacts planFacts(Scene& scene, const PlanNode& plan, const TaskProgress& progress = {},
                    bool studyConvergence = false);

/// The report of the scene's plans: header block, and per plan the
/// procedure, the incision on the face, measurements, the predicted result
/// and its stresses, the tissue thickness, then the storyboard and the
/// model's assumptions.
/// @throws std::invalid_argument when the scene has no CT volume or no plan
/// (or none of the names asked for), naming what to do.
ReportDocument buildPlanReport(Scene& scene, const ReportOptions& options, const TaskProgress& progress = {});

/// "2026-11-23": today, local time.
std::string todayIso();

} // namespace caps::report
