// The forward solve's options and summaries: validation, names, reports.
#include <iomanip>
#include <sstream>
#include <string>

#include "femreg/forward.h"
#include "forward/quasi_static_solver.h"

namespace femreg {
bool ForwardOptions::IsValid(std::string* error) const {
  // The scene's keys by their table (femreg/forward.h); the program's own by hand.
  std::ostringstream os;
  if (!CheckFieldRanges(*this, error)) {
    return false;
  } else if (!(std::isfinite(min_step) && min_step > 0 && min_step < 1)) {
    os << "min_step must be in (0, 1) (got " << min_step << ")";
  } else if (watchdog_steps < 0) {
    os << "watchdog_steps must be >= 0 (got " << watchdog_steps << ")";
  } else if (num_threads < 0) {
    os << "num_threads must be >= 0 (got " << num_threads << "; 0 = OpenMP's default)";
  } else {
    return true;
  }
  if (error) *error = os.str();
  return false;
}

const char* ToString(ForwardTangent tangent) {
  switch (tangent) {
    case ForwardTangent::kWarped:
      return "warped";
    case ForwardTangent::kProjected:
      return "projected";
    case ForwardTangent::kFull:
      return "full";
  }
  return "unknown";
}

bool FromString(const std::string& name, ForwardTangent* tangent) {
  if (name == "warped") {
    *tangent = ForwardTangent::kWarped;
  } else if (name == "projected") {
    *tangent = ForwardTangent::kProjected;
  } else if (name == "full") {
    *tangent = ForwardTangent::kFull;
  } else {
    return false;
  }
  return true;
}

const char* ToString(ForwardTermination termination) {
  switch (termination) {
    case ForwardTermination::kNotRun:
      return "NOT_RUN";
    case ForwardTermination::kConverged:
      return "CONVERGED";
    case ForwardTermination::kMaxIterations:
      return "MAX_ITERATIONS";
    case ForwardTermination::kLineSearchFailed:
      return "LINE_SEARCH_FAILED";
    case ForwardTermination::kFactorizationFailed:
      return "FACTORIZATION_FAILED";
    case ForwardTermination::kInvalidInput:
      return "INVALID_INPUT";
  }
  return "UNKNOWN";
}

bool ForwardSummary::IsSolutionUsable() const {
  return termination == ForwardTermination::kConverged ||
         termination == ForwardTermination::kMaxIterations;
}

int ForwardSummary::NumNewtonIterations() const {
  int total = 0;
  for (const ForwardLoadStep& step : load_steps) total += step.iterations;
  return total;
}

namespace forward_internal {

// "5, 6, 4" (Newton iterations per load step), with "(2 projected)" where the full tangent
// fell back.
std::string IterationsPerStep(const std::vector<ForwardLoadStep>& steps) {
  std::ostringstream os;
  for (size_t i = 0; i < steps.size(); ++i) {
    os << (i ? ", " : "") << steps[i].iterations;
    if (steps[i].projected_iterations > 0) os << " (" << steps[i].projected_iterations << " projected)";
    if (steps[i].termination != ForwardTermination::kConverged) {
      os << " " << ToString(steps[i].termination);
    }
  }
  return os.str();
}

}  // namespace forward_internal

std::string ForwardSummary::BriefReport() const {
  std::ostringstream os;
  os << "Forward solve: " << ToString(termination) << ", " << NumNewtonIterations()
     << " Newton iterations in " << load_steps.size() << " load step"
     << (load_steps.size() == 1 ? "" : "s");
  if (!load_steps.empty()) os << " [" << forward_internal::IterationsPerStep(load_steps) << "]";
  os << ", |residual| " << std::scientific << std::setprecision(3) << initial_residual_norm
     << " -> " << final_residual_norm << " N, max displacement " << max_displacement << " m, ";
  if (inverted_elements > 0) os << inverted_elements << " inverted elements, ";
  os << std::fixed << std::setprecision(3) << total_time_s << " s";
  return os.str();
}

std::string ForwardSummary::FullReport() const {
  std::ostringstream os;
  os << "Forward quasi-static solve\n";
  os << "  free dofs            " << num_free_dofs << "\n";
  os << "  iter  step  it      potential (J)   |residual| (N)    step length\n";
  for (const ForwardIteration& it : iterations) {
    os << "  " << std::setw(4) << (&it - iterations.data()) << "  " << std::setw(4) << it.load_step
       << "  " << std::setw(2) << it.iteration << "  " << std::scientific << std::setprecision(6)
       << std::setw(16) << it.energy << "  " << std::setw(14) << std::setprecision(4)
       << it.residual_norm << "  " << std::setw(13) << it.step_length
       << (it.iteration > 0 && it.tangent == ForwardTangent::kProjected ? "  projected" : "")
       << "\n";
  }
  os << "  load step  factor  Newton its  projected  |residual| start -> end (N)  termination\n";
  for (const ForwardLoadStep& step : load_steps) {
    os << "  " << std::setw(9) << step.load_step << "  " << std::fixed << std::setprecision(3)
       << std::setw(6) << step.load_factor << "  " << std::setw(10) << step.iterations << "  "
       << std::setw(9) << step.projected_iterations << "  " << std::scientific
       << std::setprecision(3) << std::setw(10) << step.initial_residual_norm << " -> "
       << std::setw(10) << step.final_residual_norm << "        "
       << ToString(step.termination) << "\n";
  }
  os << std::scientific << std::setprecision(6);
  os << "  initial |residual|   " << initial_residual_norm << " N\n";
  os << "  final |residual|     " << final_residual_norm << " N\n";
  os << "  final potential      " << final_energy << " J\n";
  os << "  max displacement     " << max_displacement << " m\n";
  os << "  inverted elements    " << inverted_elements << "\n";
  os << std::fixed << std::setprecision(4);
  os << "  factorization time   " << factorization_time_s << " s\n";
  os << "  threads              " << num_threads << "\n";
  os << "  total time           " << total_time_s << " s\n";
  os << "  termination          " << ToString(termination) << ": " << message << "\n";
  return os.str();
}

}  // namespace femreg
