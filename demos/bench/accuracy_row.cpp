#include "accuracy_row.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace gpucol::bench {
namespace {

std::string cell(double value) {
  if (std::isnan(value)) return "";
  std::ostringstream out;
  out << std::setprecision(9) << value;
  return out.str();
}

// Quotes a text cell when it holds a comma or a quote (machine names may).
std::string textCell(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace

void writeAccuracyCsv(const std::vector<AccuracyRow>& rows, const std::string& path, const std::string& machine,
                      const std::string& device) {
  std::ofstream csv(path);
  if (!csv) throw std::runtime_error("cannot write " + path);
  csv << "study,scene,setting,default,time_ms,missed_pairs,false_pairs,depth_error_m,normal_error_deg,contacts,"
         "broadphase_missed,broadphase_extra,guess_error_rate,height_drift_m,penetration_m,reduction_resolution,"
         "triangles_per_leaf,precision,mapping_sqrt,cell_rule,time_step_s,machine,device\n";
  for (const AccuracyRow& r : rows) {
    csv << textCell(r.study) << ',' << textCell(r.scene) << ',' << textCell(r.setting) << ',' << (r.isDefault ? 1 : 0)
        << ',' << cell(r.timeMs) << ',' << cell(r.missedPairs) << ',' << cell(r.falsePairs) << ','
        << cell(r.depthError) << ',' << cell(r.normalErrorDeg) << ',' << cell(r.contacts) << ','
        << cell(r.broadphaseMissed) << ',' << cell(r.broadphaseExtra) << ',' << cell(r.guessErrorRate) << ','
        << cell(r.heightDrift) << ',' << cell(r.penetration) << ',' << textCell(r.reductionResolution) << ','
        << textCell(r.trianglesPerLeaf) << ',' << textCell(r.precision) << ',' << textCell(r.mappingSqrt) << ','
        << textCell(r.cellRule) << ',' << textCell(r.timeStep) << ',' << textCell(machine) << ','
        << textCell(device) << '\n';
  }
  if (!csv) throw std::runtime_error("error while writing " + path);
}

void printAccuracyRow(const AccuracyRow& r) {
  std::cout << "  " << std::left << std::setw(13) << r.study << std::setw(26) << r.scene << std::setw(12)
            << (r.setting + (r.isDefault ? "*" : "")) << std::right << std::setprecision(4);
  const auto field = [](const char* name, double value) {
    if (!std::isnan(value)) std::cout << "  " << name << "=" << value;
  };
  field("ms", r.timeMs);
  field("missed", r.missedPairs);
  field("false", r.falsePairs);
  field("depth_err", r.depthError);
  field("normal_err_deg", r.normalErrorDeg);
  field("contacts", r.contacts);
  field("bp_missed", r.broadphaseMissed);
  field("bp_extra", r.broadphaseExtra);
  field("guess_err", r.guessErrorRate);
  field("drift", r.heightDrift);
  field("penetration", r.penetration);
  std::cout << std::endl;
}

}  // namespace gpucol::bench
