// VTU (VTK XML unstructured grid): reading with femreg's own reader (vtu_reader.cc) into a
// tetrahedral mesh, and writing through VTK, whose error messages are captured and returned
// in a Status instead of being printed.
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDoubleArray.h>
#include <vtkIntArray.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSMPTools.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

#include "femreg/io.h"
#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {
namespace {

// Collects everything VTK would print while it is installed as the output window.
class CapturingOutputWindow : public vtkOutputWindow {
 public:
  static CapturingOutputWindow* New();
  vtkTypeMacro(CapturingOutputWindow, vtkOutputWindow);
  void DisplayText(const char* text) override { Append(text); }
  void DisplayErrorText(const char* text) override { Append(text); }
  void DisplayWarningText(const char* text) override {}
  void DisplayGenericWarningText(const char* text) override {}
  void DisplayDebugText(const char* text) override {}
  std::string text;

 private:
  void Append(const char* t) {
    if (t != nullptr && text.size() < 4000) text += t;
  }
};
vtkStandardNewMacro(CapturingOutputWindow);

// Observer for a VTK object's ErrorEvent.
class ErrorObserver : public vtkCommand {
 public:
  static ErrorObserver* New() { return new ErrorObserver; }
  void Execute(vtkObject*, unsigned long event, void* data) override {
    if (event == vtkCommand::ErrorEvent && data != nullptr && text.size() < 4000) {
      text += static_cast<const char*>(data);
    }
  }
  std::string text;
};

std::mutex& VtkMutex() {
  static std::mutex mutex;
  return mutex;
}

// Installs a capturing output window for its lifetime (VTK's output window is global).
class ScopedVtkCapture {
 public:
  ScopedVtkCapture() : lock_(VtkMutex()) {
    previous_ = vtkOutputWindow::GetInstance();
    window_ = vtkSmartPointer<CapturingOutputWindow>::New();
    vtkOutputWindow::SetInstance(window_);
    // VTK 9 also logs errors to stderr through vtkLogger before the output window.
    previous_verbosity_ = vtkLogger::GetCurrentVerbosityCutoff();
    vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  }
  ~ScopedVtkCapture() {
    vtkLogger::SetStderrVerbosity(previous_verbosity_);
    vtkOutputWindow::SetInstance(previous_);
  }
  std::string text() const { return window_->text; }

 private:
  std::lock_guard<std::mutex> lock_;
  vtkSmartPointer<vtkOutputWindow> previous_;
  vtkSmartPointer<CapturingOutputWindow> window_;
  vtkLogger::Verbosity previous_verbosity_ = vtkLogger::VERBOSITY_WARNING;
};

// VTK's distinct messages without the file/line/class prefixes, joined by "; ".
std::string Summarize(const std::string& text) {
  std::istringstream in(text);
  std::string line, joined;
  while (std::getline(in, line)) {
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos) continue;
    line = line.substr(start);
    if (line.rfind("ERROR: In ", 0) == 0 || line.rfind("Warning: In ", 0) == 0) continue;
    const size_t paren = line.find("): ");
    if (paren != std::string::npos && paren < 80) line = line.substr(paren + 3);
    if (line.rfind("Algorithm ", 0) == 0) break;  // then a dump of the pipeline request
    if (line.size() > 200) line = line.substr(0, 200) + "...";
    if (joined.find(line) != std::string::npos) continue;
    if (joined.size() > 300) break;
    joined += (joined.empty() ? "" : "; ") + line;
  }
  return joined.empty() ? "VTK could not read it" : joined;
}

// The first one-component cell array of `piece` named like a region id, or null.
const VtuArray* RegionArray(const VtuPiece& piece) {
  for (const VtuArray& array : piece.cell_data) {
    if (array.components == 1 && LooksLikeRegionName(array.name)) return &array;
  }
  return nullptr;
}

std::atomic<int> g_temp_counter{0};

}  // namespace

void UseSequentialVtk() {
  static std::once_flag once;
  std::call_once(once, [] { vtkSMPTools::Initialize(1); });
}

Status ReadVtuFile(const std::string& path, RawTetMesh* raw) {
  VtuGrid grid;
  Status s = ReadVtuGrid(path, &grid);
  if (!s.ok()) return s;
  const VtuArray* first_region = RegionArray(grid.pieces[0]);
  const std::string region_name = first_region != nullptr ? first_region->name : std::string();
  const VtuPiece piece = MergePieces(std::move(grid));
  const long long np = static_cast<long long>(piece.points.size());
  if (np == 0) return FileError(path, 0, "no points (empty or unreadable grid)");
  for (long long i = 0; i < np; ++i) {
    const std::array<double, 3>& point = piece.points[static_cast<size_t>(i)];
    if (!std::isfinite(point[0]) || !std::isfinite(point[1]) || !std::isfinite(point[2])) {
      std::ostringstream os;
      os << "point " << i << " has a non-finite coordinate";
      return FileError(path, 0, os.str());
    }
  }
  raw->vertices = piece.points;
  // The region ids: the array the first piece names, which every piece must have.
  const VtuArray* region = nullptr;
  if (!region_name.empty()) {
    for (const VtuArray& array : piece.cell_data) {
      if (array.components == 1 && array.name == region_name) region = &array;
    }
    if (region == nullptr) {
      return FileError(path, 0, "a piece has no cell array " + Quoted(region_name) +
                                    " (the region ids of piece 0)");
    }
  }
  for (size_t c = 0; c < piece.types.size(); ++c) {
    if (piece.types[c] != VTK_TETRA) continue;
    const long long begin = piece.offsets[c], count = piece.offsets[c + 1] - begin;
    if (count != 4) {
      std::ostringstream os;
      os << "cell " << c << " is a tetrahedron with " << count << " points";
      return FileError(path, 0, os.str());
    }
    std::array<int, 4> tet;
    for (int k = 0; k < 4; ++k) {
      const long long v = piece.connectivity[static_cast<size_t>(begin + k)];
      if (v < 0 || v >= np) {
        std::ostringstream os;
        os << "cell " << c << " refers to point " << v << ", outside 0.." << np - 1
           << " (index out of range)";
        return FileError(path, 0, os.str());
      }
      tet[k] = static_cast<int>(v);
    }
    raw->tets.push_back(tet);
    int id = 0;
    const double value = region == nullptr ? 0.0 : region->values[c];
    if (region != nullptr && !RegionIdFrom(value, &id)) {
      std::ostringstream os;
      os << "cell " << c << ": region value " << value << " in array " << Quoted(region->name)
         << " is not a region id (an integer in the range of int)";
      return FileError(path, 0, os.str());
    }
    raw->regions.push_back(id);
  }
  if (raw->tets.empty()) return FileError(path, 0, "no tetrahedra (no cells of VTK type 10)");
  return Status::Ok();
}

// A temporary name in the folder of `path`.
std::string TemporaryPathFor(const std::string& path) {
  std::ostringstream os;
  os << path << ".tmp." << getpid() << "." << g_temp_counter++;
  return os.str();
}

}  // namespace internal

Status WriteVtu(const std::string& path, const TetMesh& mesh, const Vertices& positions,
                const std::vector<MeshField>& fields) {
  const int nv = mesh.num_vertices(), nt = mesh.num_tets();
  if (positions.rows() != nv) {
    std::ostringstream os;
    os << path << ": positions have " << positions.rows() << " rows, the mesh " << nv
       << " vertices";
    return Status::Error(os.str());
  }
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(nv);
  for (int v = 0; v < nv; ++v) points->SetPoint(v, positions(v, 0), positions(v, 1), positions(v, 2));
  grid->SetPoints(points);
  grid->Allocate(nt);
  for (int t = 0; t < nt; ++t) {
    const vtkIdType ids[4] = {mesh.tets(t, 0), mesh.tets(t, 1), mesh.tets(t, 2), mesh.tets(t, 3)};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  vtkNew<vtkIntArray> region;
  region->SetName("region");
  region->SetNumberOfTuples(nt);
  for (int t = 0; t < nt; ++t) region->SetValue(t, mesh.region.size() == nt ? mesh.region(t) : 0);
  grid->GetCellData()->AddArray(region);
  for (const MeshField& field : fields) {
    const Eigen::Index rows = field.per_cell ? nt : nv;
    if (field.name.empty() || field.name == "region" || field.values.rows() != rows ||
        (field.values.cols() != 1 && field.values.cols() != 3)) {
      std::ostringstream os;
      os << path << ": field '" << field.name << "' must have a name other than 'region', "
         << rows << " rows (one per " << (field.per_cell ? "element" : "vertex")
         << ") and 1 or 3 columns, it has " << field.values.rows() << " by "
         << field.values.cols();
      return Status::Error(os.str());
    }
    vtkNew<vtkDoubleArray> array;
    array->SetName(field.name.c_str());
    array->SetNumberOfComponents(static_cast<int>(field.values.cols()));
    array->SetNumberOfTuples(rows);
    for (Eigen::Index r = 0; r < rows; ++r) {
      for (Eigen::Index c = 0; c < field.values.cols(); ++c) {
        array->SetComponent(r, static_cast<int>(c), field.values(r, c));
      }
    }
    if (field.per_cell) {
      grid->GetCellData()->AddArray(array);
    } else {
      grid->GetPointData()->AddArray(array);
    }
  }

  const std::string temp = internal::TemporaryPathFor(path);
  int ok = 0;
  std::string errors;
  {
    internal::ScopedVtkCapture capture;
    internal::UseSequentialVtk();
    vtkNew<vtkXMLUnstructuredGridWriter> writer;
    vtkNew<internal::ErrorObserver> observer;
    writer->AddObserver(vtkCommand::ErrorEvent, observer);
    writer->SetFileName(temp.c_str());
    writer->SetInputData(grid);
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    // zlib at its fastest level: `femreg register` writes one of these per object and frame, and
    // the doubles compress little at any level
    // (docs/notes/2026-11-28-figures-from-code-comments.md).
    writer->SetCompressorTypeToZLib();
    writer->SetCompressionLevel(1);
    ok = writer->Write();
    errors = observer->text + capture.text();
  }
  if (ok != 1 || !errors.empty()) {
    std::remove(temp.c_str());
    return Status::Error(path + ": cannot write VTU: " +
                         (errors.empty() ? std::string("write failed") : internal::Summarize(errors)));
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    return Status::Error(path + ": cannot rename the temporary file into place");
  }
  return Status::Ok();
}

}  // namespace femreg
