#include "eval_forces.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "femreg/results.h"

namespace fs = std::filesystem;

namespace femreg {
namespace cli {

namespace {

// eval.csv's contact-force cell: empty without one.
std::string ContactCell(double error) {
  if (std::isnan(error)) return ",";
  char buf[64];
  std::snprintf(buf, sizeof(buf), ",%.6f", error);
  return buf;
}

// A ratio as a percentage; empty when it is undefined (a true force of 0).
std::string Percent(double ratio, const char* format) {
  if (std::isnan(ratio)) return "";
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, 100.0 * ratio);
  return buf;
}

}  // namespace

std::string ForceReport::Cells(int f) const {
  const auto it = of_frame.find(f);
  if (it == of_frame.end()) return contact ? ",,,," : ",,,";
  const ForceError& e = errors[it->second];
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%.6f,%.6f,%s,%.6f", e.true_force, e.error,
                Percent(e.relative, "%.3f").c_str(), e.torque_error);
  return std::string(buf) + (contact ? ContactCell(e.contact_error) : "");
}

std::string ForceReport::MedianCells() const {
  const ForceErrorMedians m = MedianForceErrors(errors);
  char buf[160];
  std::snprintf(buf, sizeof(buf), ",%.6f,%s,%.6f", m.error, Percent(m.relative, "%.3f").c_str(),
                m.torque_error);
  return std::string(buf) + (contact ? ContactCell(m.contact_error) : "");
}

void ForceReport::Print() const {
  std::printf("Resultant external force against %s (estimated in stats.csv):\n",
              truth_path.c_str());
  std::printf("%6s | %9s %9s %8s | %13s\n", "frame", "true N", "error N", "error %",
              "torque err Nm");
  for (const ForceError& e : errors) {
    const std::string pct = Percent(e.relative, "%8.2f");
    std::printf("%6d | %9.4f %9.4f %8s | %13.3e\n", e.frame, e.true_force, e.error,
                pct.empty() ? "-" : pct.c_str(), e.torque_error);
  }
  const ForceErrorMedians m = MedianForceErrors(errors);
  const std::string median = Percent(m.relative, "%.2f");
  std::printf("%s\n%6s | %9s %9.4f %8s | %13.3e\n", std::string(52, '-').c_str(), "median", "",
              m.error, median.empty() ? "-" : median.c_str(), m.torque_error);
  int undefined = 0;
  for (const ForceError& e : errors) undefined += std::isnan(e.relative);
  std::printf("Median resultant-force error: %s%% of the true force over %zu frames",
              median.empty() ? "-" : median.c_str(), errors.size() - undefined);
  if (undefined > 0) {
    std::printf(" (%d more with a true force of 0: no relative error)", undefined);
  }
  std::printf(".\n");
  if (contact) {
    int with = 0;
    for (const ForceError& e : errors) with += !std::isnan(e.contact_error);
    std::printf("Median error of the obstacles' push (contact_force_*_N): %.4f N over %d frames, the true "
                "push's median %.4f N.\n",
                m.contact_error, with, m.true_contact);
  }
  std::vector<ForceError> switched;
  for (const ForceError& e : errors) {
    if (std::binary_search(estimated_frames.begin(), estimated_frames.end(), e.frame)) switched.push_back(e);
  }
  if (estimated == 0 && !switched.empty()) {
    const std::string pct = Percent(MedianForceErrors(switched).relative, "%.2f");
    std::printf("The run estimated the forces in %zu of these %zu frames (forces.when_occluded: an occluder "
                "touched the body); their median error: %s%% of the true force. The other frames' are their "
                "data term's pull and their contacts' push.\n",
                switched.size(), errors.size(), pct.empty() ? "-" : pct.c_str());
  } else if (estimated == 0) {
    std::printf("The run did not estimate the forces: these are its data term's pull and its contacts' "
                "push (register with --set registration.forces.estimate=true for an estimate).\n");
  }
}

Status CompareForceFiles(const std::string& result, const std::string& truth_dir, size_t num_frames,
                         ForceReport* report) {
  const fs::path truth_path = fs::path(truth_dir) / "forces.csv";
  const fs::path stats_path = fs::path(result) / "stats.csv";
  report->truth_path = truth_path.string();
  if (!fs::exists(truth_path)) return Status::Ok();
  std::vector<ForceFrame> truth, estimated;
  bool has_columns = false;
  Status status = ReadForces(truth_path.string(), &truth, &has_columns);
  if (!status.ok()) return status;
  if (!has_columns) {
    std::string header = "frame";
    for (const char* c : kForceColumns) header += std::string(",") + c;
    return Status::Error(truth_path.string() + ": expected the header " + header);
  }
  if (!fs::exists(stats_path)) {
    report->note = "Forces: " + truth_path.string() + " is there, " + stats_path.string() +
                   " is not: no force error.";
    return Status::Ok();
  }
  status = ReadForces(stats_path.string(), &estimated, &has_columns);
  if (!status.ok()) return status;
  if (!has_columns) return Status::Ok();  // a result without force estimates
  const fs::path summary = fs::path(result) / "summary.json";
  std::error_code ec;
  if (fs::exists(summary, ec)) {
    const Status read = ReadSummaryForcesEstimated(summary.string(), &report->estimated);
    if (!read.ok()) std::cerr << "femreg eval: warning: " << read.message() << "\n";
  }
  const auto beyond = [&](const ForceFrame& f) { return f.frame >= static_cast<int>(num_frames); };
  truth.erase(std::remove_if(truth.begin(), truth.end(), beyond), truth.end());
  report->errors = CompareForces(estimated, truth);
  for (const ForceFrame& f : estimated) {
    if (f.estimated == 1) report->estimated_frames.push_back(f.frame);
  }
  std::sort(report->estimated_frames.begin(), report->estimated_frames.end());
  for (size_t i = 0; i < report->errors.size(); ++i) report->of_frame[report->errors[i].frame] = i;
  report->compared = !report->errors.empty();
  for (const ForceError& e : report->errors) report->contact = report->contact || !std::isnan(e.contact_error);
  if (!report->compared) {
    report->note = "Forces: no frame of " + stats_path.string() + " has an estimate that " +
                   truth_path.string() + " has the truth of.";
  } else if (!report->contact &&
             std::any_of(truth.begin(), truth.end(), [](const ForceFrame& f) { return f.has_contact; })) {
    report->note = "Forces: " + truth_path.string() + " has the obstacles' push (contact_force_*_N), " +
                   stats_path.string() + " has it in no frame it has the truth of (a result written " +
                   "before stats.csv had those columns?): no obstacle-push error.";
  }
  return Status::Ok();
}

}  // namespace cli
}  // namespace femreg
