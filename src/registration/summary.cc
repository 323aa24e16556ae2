#include <cstdio>
#include <sstream>

#include "femreg/registration.h"

namespace femreg {

bool FrameSummary::IsSolutionUsable() const {
  return termination == TerminationType::kConverged ||
         termination == TerminationType::kMaxIterations ||
         termination == TerminationType::kTimeBudget || termination == TerminationType::kStalled;
}

std::string FrameSummary::BriefReport() const {
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "frame %d: %s, %d outer / %d inner iterations, energy %.4g -> %.4g, "
                "rms %.3f mm, %d+%d pairs (%d rejected), %.1f ms",
                frame, ToString(termination), outer_iterations, inner_iterations, initial.total(),
                final.total(), rms_residual * 1e3, model_to_cloud, cloud_to_model, rejected,
                time.total * 1e3);
  std::string brief = buf;
  if (!initial_pose.empty() && initial_pose != "given") {
    brief += ", initial pose " + initial_pose + (pose_ambiguous ? " (ambiguous)" : "");
  }
  if (large_motion_restarts > 0) brief += ", large motion: started again stiff";
  if (crushed_restarts > 0) brief += ", crushed element: started again stiff";
  if (implausible_points > implausible_carried) {
    brief += ", " + std::to_string(implausible_points - implausible_carried) + " implausible points: " +
             (implausible_restarts > 0 ? "started again without them" : "left out");
  }
  if (contacts > 0 || time.collision > 0) {
    std::snprintf(buf, sizeof(buf), ", %d contacts, deepest %.3f mm, gap %.3f mm", contacts,
                  max_penetration * 1e3, min_gap * 1e3);
    brief += buf;
  }
  return brief;
}

std::string FrameSummary::FullReport() const {
  std::ostringstream os;
  char buf[512];
  os << "Frame " << frame << "\n";
  if (!initial_pose.empty()) {
    os << "  initial pose: " << initial_pose << (pose_ambiguous ? " (ambiguous)" : "") << "\n";
  }
  if (large_motion_restarts > 0) {
    os << "  large motion: iteration 1 moved the bulk of the vertices more than 3 mean edges; the frame "
          "started again from iteration 2, the elastic weight x100, x30, x10, x3, then x1, pairing only "
          "surface that faces the sensor\n";
  }
  if (crushed_restarts > 0) {
    os << "  crushed element: an outer iteration left an element below solver.stiff_restart_volume of its "
          "volume at the frame's start and at rest; the frame started again, the elastic weight x100, x30, "
          "x10, x3, then x1, pairing only surface that faces the sensor\n";
  }
  if (implausible_carried > 0) {
    os << "  implausible points: " << implausible_carried
       << " cloud points near the last frame's implausible ones were left out from the start\n";
  }
  if (implausible_points > implausible_carried) {
    os << "  implausible points: " << implausible_points - implausible_carried << " cloud points pulled elements beyond "
          "data.max_strain_step; ";
    if (implausible_restarts > 0) {
      os << "the frame started again without them (" << implausible_restarts << "x)\n";
    } else {
      os << "too few to have moved the shape, the frame went on without them\n";
    }
  }
  os << "  cloud: " << cloud_points << " points, " << nonfinite_dropped << " non-finite dropped, "
     << flying_pixels << " flying pixels, " << points_used << " used";
  if (depth_offset != 0.0) os << ", depth offset " << depth_offset * 1e3 << " mm taken off";
  os << "\n";
  os << "  iter   E_data      E_elastic   E_temporal  E_anchor    E_total     m2c    c2m    rej  "
        "inner  rms(mm)  move(mm)  ms\n";
  for (const OuterIteration& it : iterations) {
    std::snprintf(buf, sizeof(buf),
                  "  %4d   %-10.4g  %-10.4g  %-10.4g  %-10.4g  %-10.4g  %-6d %-6d %-4d %-6d %-8.3f "
                  "%-9.3f %.1f\n",
                  it.iteration, it.after.data, it.after.elastic, it.after.temporal, it.after.anchor,
                  it.after.total(), it.model_to_cloud, it.cloud_to_model, it.rejected,
                  it.inner_iterations, it.rms_residual * 1e3, it.max_move * 1e3, it.time_s * 1e3);
    os << buf;
  }
  std::snprintf(buf, sizeof(buf),
                "  time (ms): preprocess %.2f, prealign %.2f, rotations %.2f, correspondences "
                "%.2f, build %.2f, solve %.2f, outputs %.2f, total %.2f\n",
                time.preprocess * 1e3, time.prealign * 1e3, time.rotations * 1e3,
                time.correspondences * 1e3, time.build * 1e3, time.solve * 1e3, time.outputs * 1e3,
                time.total * 1e3);
  os << buf;
  std::snprintf(buf, sizeof(buf),
                "  solve (ms): assembly %.2f, factorization %.2f (%d), linear solves %.2f (%d, %d "
                "PCG iterations), energy evaluations %.2f; stopped by %s\n",
                time.assembly * 1e3, time.factorization * 1e3, factorizations,
                time.linear_solve * 1e3, linear_solves, pcg_iterations, time.evaluation * 1e3,
                stopped_by.c_str());
  os << buf;
  if (contacts > 0 || time.collision > 0) {
    std::snprintf(buf, sizeof(buf),
                  "  collision: E %.4g, %d contacts (%d object, %d obstacle), deepest penetration "
                  "%.3f mm, smallest gap %.3f mm, detection %.2f ms\n",
                  final.collision, contacts, object_contacts, obstacle_contacts,
                  max_penetration * 1e3, min_gap * 1e3, time.collision * 1e3);
    os << buf;
  }
  if (!fractures.empty() || time.fracture > 0) {
    std::snprintf(buf, sizeof(buf), "  fracture: %zu node splits, detection and splits %.2f ms\n",
                  fractures.size(), time.fracture * 1e3);
    os << buf;
    for (const FractureEvent& e : fractures) {
      std::snprintf(buf, sizeof(buf),
                    "    object %d node %d (initial %d) after iteration %d: measure %.4g Pa > %.4g, "
                    "plane normal (%.3f, %.3f, %.3f), %d elements removed\n",
                    e.object, e.node, e.original_node, e.iteration, e.measure, e.toughness,
                    e.normal.x(), e.normal.y(), e.normal.z(), e.removed_elements);
      os << buf;
    }
  }
  os << "  termination: " << ToString(termination) << " (" << message << ")\n";
  return os.str();
}

}  // namespace femreg
