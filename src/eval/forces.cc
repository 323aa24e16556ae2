// The true external force per frame (a dataset's forces.csv), the estimated one (the same
// columns in a register result's stats.csv), and the error of one against the other.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <system_error>

#include "femreg/ground_truth.h"
#include "femreg/io.h"

namespace femreg {

const char* const kForceColumns[6] = {"force_x_N",   "force_y_N",   "force_z_N",
                                      "torque_x_Nm", "torque_y_Nm", "torque_z_Nm"};
const char* const kContactForceColumns[3] = {"contact_force_x_N", "contact_force_y_N", "contact_force_z_N"};

namespace {

// The cells of one CSV line: commas split them except inside double quotes, where "" is a
// quote (stats.csv's message is quoted and may hold commas).
std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cells.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cells.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.emplace_back();
    } else if (c != '\r') {
      cells.back() += c;
    }
  }
  return cells;
}

std::string Trim(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t\r") - begin + 1);
}

// The whole cell as a finite number ("+" allowed in front).
bool ParseNumber(const std::string& cell, double* value) {
  const char* begin = cell.data();
  const char* end = begin + cell.size();
  if (begin < end && *begin == '+') ++begin;
  const std::from_chars_result r = std::from_chars(begin, end, *value);
  return r.ec == std::errc() && r.ptr == end && begin < end && std::isfinite(*value);
}

}  // namespace

Status WriteForces(const std::string& path, const std::vector<ForceFrame>& frames) {
  std::ostringstream os;
  os << "frame";
  for (const char* column : kForceColumns) os << "," << column;
  os << "\n";
  // Fixed 1e-9 resolution (N, N m), as the ground truth's positions have one: a component
  // that should be 0 (1e-17 one way, -1e-17 another) does not reach the file.
  auto cell = [](double v) {
    double r = std::round(v * 1e9) / 1e9;
    if (r == 0.0) r = 0.0;  // no negative zero
    char buf[48];
    std::snprintf(buf, sizeof(buf), "%.9f", r);
    return std::string(buf);
  };
  for (const ForceFrame& f : frames) {
    os << f.frame;
    for (int i = 0; i < 3; ++i) os << "," << cell(f.force(i));
    for (int i = 0; i < 3; ++i) os << "," << cell(f.torque(i));
    os << "\n";
  }
  return WriteFileAtomically(path, os.str());
}

Status ReadForces(const std::string& path, std::vector<ForceFrame>* frames, bool* has_columns) {
  frames->clear();
  *has_columns = false;
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open");
  std::string line;
  if (!std::getline(in, line)) return Status::Error(path + ": empty (expected a header row)");
  const std::vector<std::string> header = SplitCsvLine(line);
  std::map<std::string, int> at;
  for (size_t i = 0; i < header.size(); ++i) at.emplace(Trim(header[i]), static_cast<int>(i));
  auto column = [&at](const char* name) {
    const auto it = at.find(name);
    return it == at.end() ? -1 : it->second;
  };
  int columns[7];
  columns[0] = column("frame");
  for (int k = 0; k < 6; ++k) columns[k + 1] = column(kForceColumns[k]);
  if (*std::min_element(columns, columns + 7) < 0) return Status::Ok();
  *has_columns = true;
  int contact[3];
  for (int k = 0; k < 3; ++k) contact[k] = column(kContactForceColumns[k]);
  const bool with_contact = *std::min_element(contact, contact + 3) >= 0;
  if (!with_contact && *std::max_element(contact, contact + 3) >= 0) {  // some, not all three
    for (int k = 0; k < 3; ++k) {
      if (contact[k] < 0) return Status::Error(path + ": the header has contact force columns but not " + kContactForceColumns[k]);
    }
  }
  const int estimated_at = column("forces_estimated");
  const int needed = std::max({*std::max_element(columns, columns + 7),
                               with_contact ? *std::max_element(contact, contact + 3) : 0, estimated_at}) + 1;
  for (int number = 2; std::getline(in, line); ++number) {
    if (Trim(line).empty()) continue;
    const std::vector<std::string> cells = SplitCsvLine(line);
    const std::string where = path + ":" + std::to_string(number) + ": ";
    if (static_cast<int>(cells.size()) < needed) {
      return Status::Error(where + "the row has " + std::to_string(cells.size()) +
                           " cells, the header names column " + std::to_string(needed));
    }
    int empty = 0;
    for (int k = 1; k < 7; ++k) empty += Trim(cells[columns[k]]).empty();
    if (empty == 6) continue;  // no estimate in this frame
    double values[7];
    for (int k = 0; k < 7; ++k) {
      const std::string cell = Trim(cells[columns[k]]);
      if (!ParseNumber(cell, &values[k])) {
        return Status::Error(where + (k == 0 ? "frame" : kForceColumns[k - 1]) +
                             " is not a number ('" + cell + "')");
      }
    }
    if (values[0] < 0 || values[0] != std::floor(values[0])) {
      return Status::Error(where + "frame must be a whole number >= 0");
    }
    ForceFrame f;
    f.frame = static_cast<int>(values[0]);
    f.force = Eigen::Vector3d(values[1], values[2], values[3]);
    f.torque = Eigen::Vector3d(values[4], values[5], values[6]);
    if (with_contact) {
      int filled = 0, empty_at = 0;
      for (int k = 0; k < 3; ++k) {
        const std::string cell = Trim(cells[contact[k]]);
        if (cell.empty()) {
          empty_at = k;
          continue;
        }
        if (!ParseNumber(cell, &f.contact(k))) {
          return Status::Error(where + kContactForceColumns[k] + " is not a number ('" + cell + "')");
        }
        ++filled;
      }
      // All three or none (a frame without the push).
      if (filled != 0 && filled != 3) return Status::Error(where + kContactForceColumns[empty_at] + " is empty");
      f.has_contact = filled == 3;
    }
    if (estimated_at >= 0) {
      const std::string cell = Trim(cells[estimated_at]);
      if (cell != "0" && cell != "1") return Status::Error(where + "forces_estimated must be 0 or 1 ('" + cell + "')");
      f.estimated = cell == "1" ? 1 : 0;
    }
    frames->push_back(f);
  }
  return Status::Ok();
}

std::vector<ForceError> CompareForces(const std::vector<ForceFrame>& estimated,
                                      const std::vector<ForceFrame>& truth) {
  std::map<int, const ForceFrame*> by_frame;
  for (const ForceFrame& e : estimated) by_frame.emplace(e.frame, &e);
  std::vector<ForceError> out;
  for (const ForceFrame& t : truth) {
    const auto it = by_frame.find(t.frame);
    if (it == by_frame.end()) continue;
    ForceError e;
    e.frame = t.frame;
    e.true_force = t.force.norm();
    e.error = (it->second->force - t.force).norm();
    e.relative =
        e.true_force > 0 ? e.error / e.true_force : std::numeric_limits<double>::quiet_NaN();
    e.torque_error = (it->second->torque - t.torque).norm();
    if (t.has_contact && it->second->has_contact) {
      e.contact_error = (it->second->contact - t.contact).norm();
      e.true_contact = t.contact.norm();
    }
    out.push_back(e);
  }
  return out;
}

ForceErrorMedians MedianForceErrors(const std::vector<ForceError>& errors) {
  auto median = [&](double ForceError::*field) {
    std::vector<double> values;
    for (const ForceError& e : errors)
      if (!std::isnan(e.*field)) values.push_back(e.*field);
    if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  };
  ForceErrorMedians m;
  m.error = median(&ForceError::error);
  m.relative = median(&ForceError::relative);
  m.torque_error = median(&ForceError::torque_error);
  m.contact_error = median(&ForceError::contact_error);
  m.true_contact = median(&ForceError::true_contact);
  return m;
}

}  // namespace femreg
