#pragma once

#include <limits>
#include <string>
#include <vector>

namespace gpucol::bench {

/// Not measured for this row (written as an empty CSV cell).
inline constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();

/// One setting of one knob of `gpucol-bench accuracy`: its time, each error measured for it, and the knobs it ran
/// with. Errors that do not apply to a study stay kNotMeasured.
struct AccuracyRow {
  std::string study;    ///< Which knob is swept: "reduction", "tessellation", "leaf_size", "precision", ...
  std::string scene;    ///< The scene the row measured.
  std::string setting;  ///< The knob's value in words ("4", "float", "1/60").
  bool isDefault = false;  ///< True for the setting gpucol ships with.

  double timeMs = kNotMeasured;  ///< Median time of the measured operation (the study says which).
  double missedPairs = kNotMeasured;    ///< Intersecting triangle pairs the reference finds and gpucol does not.
  double falsePairs = kNotMeasured;     ///< Pairs gpucol reports intersecting that the reference does not.
  double depthError = kNotMeasured;     ///< Deepest contact's |depth| minus the analytic penetration (metres).
  double normalErrorDeg = kNotMeasured; ///< Angle between the contacts' resultant push and the analytic normal.
  double contacts = kNotMeasured;       ///< Contacts kept (after reduction).
  double broadphaseMissed = kNotMeasured;  ///< Overlapping proxy pairs the broad phase did not report.
  double broadphaseExtra = kNotMeasured;   ///< Reported proxy pairs whose boxes do not overlap.
  double guessErrorRate = kNotMeasured;    ///< Share of mapping-function guesses off by at least one row.
  double heightDrift = kNotMeasured;       ///< |final - start height| of a stack's top box (metres).
  double penetration = kNotMeasured;       ///< Deepest resting contact of a stack (metres).

  std::string reductionResolution;  ///< Knob: Config::reductionResolution.
  std::string trianglesPerLeaf;     ///< Knob: Config::trianglesPerLeaf.
  std::string precision;            ///< Knob: near phase arithmetic, "double" (gpucol's) or "float".
  std::string mappingSqrt;          ///< Knob: square root of the mapping function's guess.
  std::string cellRule;             ///< Knob: grid cell size rule and scale.
  std::string timeStep;             ///< Knob: simulation time step (seconds).
};

/// Writes `rows` as CSV with one header line, each row tagged with the machine and device it ran on.
void writeAccuracyCsv(const std::vector<AccuracyRow>& rows, const std::string& path, const std::string& machine,
                      const std::string& device);

/// Settings of one study: each study appends its rows to `rows` and prints a line per row as it goes.
struct AccuracyContext {
  std::string meshDirectory;  ///< Folder of the real meshes.
  int runs = 5;               ///< Timed repetitions per setting (the median is kept).
  bool quick = false;         ///< Smaller scenes and fewer settings, for a check that the command works.
};

/// The mesh pipeline's studies: contact reduction, tessellation of analytic shapes, leaf size, near phase
/// precision.
void runMeshAccuracyStudies(const AccuracyContext& context, std::vector<AccuracyRow>& rows);

/// The broad phase's studies: mapping-function square root, grid cell size.
void runBroadphaseAccuracyStudies(const AccuracyContext& context, std::vector<AccuracyRow>& rows);

/// The simulation's studies: time step and contact reduction in a resting stack.
void runWorldAccuracyStudies(const AccuracyContext& context, std::vector<AccuracyRow>& rows);

/// Prints one row as a line of text.
void printAccuracyRow(const AccuracyRow& row);

}  // namespace gpucol::bench
