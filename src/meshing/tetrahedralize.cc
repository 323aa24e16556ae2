// TetrahedralizeSurface: checks (surface_check.cc), the surface remeshed to the edge length
// (remesh_surface.cc) and checked again, then TetGen 1.5 as a library.
//
// TetGen is told: p (the input is a piecewise linear complex), q<ratio>/<angle> (quality),
// a<volume> (largest volume), M (never merge nearly coplanar triangles: by default TetGen
// merges neighbours within 0.1 degree of flat and re-triangulates them, which moves the
// boundary off the input, by 1e-7 of the Bunny's volume; with M the mesh fills the surface to
// rounding, 1e-14), A (a region attribute per solid, from region points), Y (keep the
// surface: no Steiner point on it) when asked or when the surface was remeshed. Cavities go in as hole points. Not Q: what TetGen
// prints (stages, warnings, statistics) is its log in the report. TetGen built with TETLIBRARY
// reports a failure by throwing an int (terminatetetgen): 1 out of memory, 2 internal error, 3
// self-intersection, 4 a very small input feature, 5 two very close facets, 10 input error.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <tetgen.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <map>
#include <new>
#include <set>
#include <sstream>
#include <vector>

#include "femreg/meshing.h"
#include "geometry/morton.h"
#include "meshing/mesh_measures.h"
#include "meshing/remesh_surface.h"
#include "meshing/surface_check.h"
#include "meshing/wrap_surface.h"
#include "parallel/stopwatch.h"

namespace femreg {
namespace {

using Clock = std::chrono::steady_clock;

using internal::Fmt;

// TetGen runs in a child process. TetGen 1.5.0 frees its memory twice when it gives up
// (terminatetetgen frees it, then throws, and the unwinding destructor frees it again: a
// segmentation fault), and it has assertions: in a child, either comes back as an error
// instead of ending the caller. The child writes the mesh through a pipe; what TetGen prints
// (progress, warnings, statistics) goes to a temporary file that becomes the log.
struct TetGenRun {
  enum class Outcome { kMesh, kGaveUp, kCrashed, kTimedOut } outcome = Outcome::kCrashed;
  int code = 0;    // kGaveUp: TetGen's error code
  int signal = 0;  // kCrashed: the signal that ended the child (0: it exited without a mesh)
  int first_number = 0;
  int num_attributes = 0;
  std::vector<double> points;      // #P * 3
  std::vector<int> tets;           // #T * 4
  std::vector<double> attributes;  // #T * num_attributes
  std::string log;
};

struct PipeHeader {
  int32_t code;  // 0: a mesh follows; otherwise TetGen's error code
  int32_t num_points, num_tets, num_attributes, first_number;
};

bool WriteAll(int fd, const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

[[noreturn]] void ChildRun(char* switches, tetgenio* in, int out_fd, int log_fd) {
  dup2(log_fd, STDOUT_FILENO);
  std::setvbuf(stdout, nullptr, _IONBF, 0);  // every line reaches the log, crash or not
  tetgenbehavior behavior;
  PipeHeader header = {10, 0, 0, 0, 0};
  tetgenio out;
  if (behavior.parse_commandline(switches)) {
    try {
      tetrahedralize(&behavior, in, &out);
      header.code = 0;
    } catch (int code) {
      header.code = code != 0 ? code : 2;
    } catch (const std::bad_alloc&) {
      header.code = 1;
    }
  }
  if (header.code == 0) {
    header.num_points = out.numberofpoints;
    header.num_tets = out.numberofcorners == 4 ? out.numberoftetrahedra : 0;
    header.num_attributes = out.numberoftetrahedronattributes;
    header.first_number = out.firstnumber;
  }
  bool ok = WriteAll(out_fd, &header, sizeof(header));
  if (ok && header.code == 0) {
    ok = WriteAll(out_fd, out.pointlist,
                  sizeof(REAL) * 3 * static_cast<size_t>(header.num_points)) &&
         WriteAll(out_fd, out.tetrahedronlist,
                  sizeof(int) * 4 * static_cast<size_t>(header.num_tets)) &&
         WriteAll(out_fd, out.tetrahedronattributelist,
                  sizeof(REAL) * static_cast<size_t>(header.num_attributes) * header.num_tets);
  }
  std::fflush(stdout);
  _exit(ok ? 0 : 1);
}

// Runs tetrahedralize(switches, in) in a child process. A non-OK status only when the child
// cannot be started or its answer is garbled; TetGen's own failures are in run->outcome.
Status RunTetGen(const std::string& switches, tetgenio* in, double time_limit_seconds,
                 TetGenRun* run) {
  *run = TetGenRun();
  std::FILE* log = std::tmpfile();
  if (log == nullptr) {
    return Status::Error(std::string("cannot create a temporary file for TetGen's log: ") +
                         std::strerror(errno));
  }
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    std::fclose(log);
    return Status::Error(std::string("cannot create a pipe for TetGen: ") + std::strerror(errno));
  }
  std::vector<char> arg(switches.begin(), switches.end());
  arg.push_back('\0');
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) {
    const int e = errno;
    close(fds[0]);
    close(fds[1]);
    std::fclose(log);
    return Status::Error(std::string("cannot start TetGen (fork): ") + std::strerror(e));
  }
  if (pid == 0) {
    close(fds[0]);
    ChildRun(arg.data(), in, fds[1], fileno(log));
  }
  close(fds[1]);

  // Read everything the child writes; kill it when the time limit is up.
  std::string bytes;
  const Clock::time_point start = Clock::now();
  bool timed_out = false;
  char buf[1 << 16];
  for (;;) {
    int wait_ms = -1;
    if (time_limit_seconds > 0.0) {
      const double left = time_limit_seconds - Seconds(start);
      if (left <= 0.0) {
        timed_out = true;
        break;
      }
      wait_ms = static_cast<int>(std::min(left * 1000.0 + 1.0, 1e9));
    }
    pollfd p = {fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) continue;  // the loop checks the time left
    const ssize_t n = read(fds[0], buf, sizeof(buf));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    bytes.append(buf, static_cast<size_t>(n));
  }
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int wstatus = 0;
  while (waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
  }
  std::fflush(log);
  std::rewind(log);
  size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), log)) > 0 && run->log.size() < (1u << 20)) {
    run->log.append(buf, n);
  }
  std::fclose(log);

  if (timed_out) {
    run->outcome = TetGenRun::Outcome::kTimedOut;
    return Status::Ok();
  }
  PipeHeader header;
  if (bytes.size() < sizeof(header)) {
    run->outcome = TetGenRun::Outcome::kCrashed;
    run->signal = WIFSIGNALED(wstatus) ? WTERMSIG(wstatus) : 0;
    return Status::Ok();
  }
  std::memcpy(&header, bytes.data(), sizeof(header));
  if (header.code != 0) {
    run->outcome = TetGenRun::Outcome::kGaveUp;
    run->code = header.code;
    return Status::Ok();
  }
  const size_t np = static_cast<size_t>(std::max(header.num_points, 0));
  const size_t nt = static_cast<size_t>(std::max(header.num_tets, 0));
  const size_t na = static_cast<size_t>(std::max(header.num_attributes, 0));
  const size_t expected =
      sizeof(header) + sizeof(REAL) * 3 * np + sizeof(int) * 4 * nt + sizeof(REAL) * na * nt;
  if (bytes.size() != expected) {
    return Status::Error("TetGen's process ended after sending " + std::to_string(bytes.size()) +
                         " of the mesh's " + std::to_string(expected) + " bytes" +
                         (WIFSIGNALED(wstatus)
                              ? " (signal " + std::to_string(WTERMSIG(wstatus)) + ")"
                              : std::string()));
  }
  const char* p = bytes.data() + sizeof(header);
  run->points.resize(3 * np);
  std::memcpy(run->points.data(), p, sizeof(REAL) * 3 * np);
  p += sizeof(REAL) * 3 * np;
  run->tets.resize(4 * nt);
  std::memcpy(run->tets.data(), p, sizeof(int) * 4 * nt);
  p += sizeof(int) * 4 * nt;
  run->attributes.resize(na * nt);
  std::memcpy(run->attributes.data(), p, sizeof(REAL) * na * nt);
  run->num_attributes = static_cast<int>(na);
  run->first_number = header.first_number;
  run->outcome = TetGenRun::Outcome::kMesh;
  return Status::Ok();
}

// The last non-empty line of TetGen's log (the stage it was in).
std::string LastLine(const std::string& log) {
  size_t end = log.find_last_not_of(" \n\r\t");
  if (end == std::string::npos) return "";
  const size_t begin = log.find_last_of('\n', end);
  return log.substr(begin == std::string::npos ? 0 : begin + 1,
                    end - (begin == std::string::npos ? 0 : begin + 1) + 1);
}

// Lines of TetGen's log that warn about something.
std::string Warnings(const std::string& log) {
  std::istringstream in(log);
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.find("Warning") != std::string::npos || line.find("Error") != std::string::npos ||
        line.find("!!") != std::string::npos) {
      out += line + "\n";
    }
  }
  return out;
}

// "N pairs of crossing triangles, e.g. a and b" from the log of a -d run (TetGen prints
// "Facet #i intersects facet #j at triangles:" and then the two corner triples).
std::string IntersectingPairs(const std::string& log, const Triangles& T) {
  std::map<std::array<int, 3>, int> row;
  for (int t = 0; t < T.rows(); ++t) {
    std::array<int, 3> key = {T(t, 0), T(t, 1), T(t, 2)};
    std::sort(key.begin(), key.end());
    row.emplace(key, t);
  }
  std::istringstream in(log);
  std::string line;
  std::set<std::pair<int, int>> pairs;  // TetGen may name a pair more than once
  int unnamed = 0;
  while (std::getline(in, line)) {
    std::array<int, 3> a, b;
    if (std::sscanf(line.c_str(), " (%d, %d, %d) and (%d, %d, %d)", &a[0], &a[1], &a[2], &b[0],
                    &b[1], &b[2]) != 6) {
      continue;
    }
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    auto ia = row.find(a), ib = row.find(b);
    if (ia == row.end() || ib == row.end()) {
      ++unnamed;
    } else {
      pairs.insert(std::minmax(ia->second, ib->second));
    }
  }
  const size_t count = pairs.size() + static_cast<size_t>(unnamed);
  if (count == 0) return "";
  std::string examples;
  int listed = 0;
  for (const auto& p : pairs) {
    if (listed++ == 5) break;
    examples +=
        (examples.empty() ? "" : ", ") + std::to_string(p.first) + "/" + std::to_string(p.second);
  }
  return std::to_string(count) + " pairs of crossing triangles" +
         (examples.empty() ? "" : " (triangles " + examples + (count > 5 ? ", ..." : "") + ")");
}

std::string TetGenFailure(int code) {
  switch (code) {
    case 1:
      return "TetGen ran out of memory (use a larger edge length)";
    case 2:
      return "TetGen hit an internal error";
    case 3:
      return "TetGen found a self-intersection (two triangles cross)";
    case 4:
      return "TetGen found a very small input feature (edges much shorter than the rest: a "
             "larger merge distance, or removing sliver triangles, helps)";
    case 5:
      return "TetGen found two very close triangles (TetGen suggests keeping the surface as "
             "it is: keep_surface)";
    case 10:
      return "TetGen rejected the input";
    default:
      return "TetGen failed with code " + std::to_string(code);
  }
}

}  // namespace

Status TetrahedralizeSurface(const Vertices& V, const Triangles& F, const MeshingOptions& options,
                             TetMesh* mesh, MeshingReport* report_out, const std::string& source) {
  return internal::Tetrahedralize(V, F, options, mesh, report_out, source, /*wrap_hint=*/true);
}

namespace internal {

Status Tetrahedralize(const Vertices& V, const Triangles& F, const MeshingOptions& given, TetMesh* mesh,
                      MeshingReport* report_out, const std::string& input_source, bool wrap_hint) {
  const Clock::time_point start = Clock::now();
  // A wrap without an edge length is meshed at its own detail, ALPHA: its triangles are far
  // finer (about the offset) and would make a mesh of hundreds of thousands of elements.
  MeshingOptions options = given;
  if (given.wrap > 0.0 && given.edge_length == 0.0 && !given.keep_surface) options.edge_length = given.wrap;
  MeshingReport local_report;
  MeshingReport& report = report_out != nullptr ? *report_out : local_report;
  report = MeshingReport();
  report.input_vertices = static_cast<int>(V.rows());
  report.input_triangles = static_cast<int>(F.rows());
  std::string error;
  if (!options.IsValid(&error)) return Status::Error(input_source + ": meshing options: " + error);

  // A broken surface (a scan's) is wrapped first where asked: the rest meshes the wrap, and
  // its messages name the wrap's triangles, not the input's.
  Vertices wrapped_vertices;
  Triangles wrapped_triangles;
  if (options.wrap > 0.0) {
    const Status wrapped =
        WrapForMeshing(V, F, options, input_source, &wrapped_vertices, &wrapped_triangles, &report);
    if (!wrapped.ok()) {
      report.total_seconds = Seconds(start);
      return wrapped;
    }
  }
  const std::string source = report.wrapped ? input_source + " wrapped at alpha " + Fmt(report.wrap_alpha)
                                            : input_source;

  // Clean and check the surface.
  const Clock::time_point check_start = Clock::now();
  internal::CheckedSurface surface;
  Status status = internal::CheckSurface(report.wrapped ? wrapped_vertices : V, report.wrapped ? wrapped_triangles : F,
                                         options.merge_distance, options.check_self_intersections, source,
                                         &surface);
  report.merged_vertices = surface.merged_vertices;
  report.unused_vertices = surface.unused_vertices;
  report.merge_distance = surface.merge_distance;
  report.surface_vertices = static_cast<int>(surface.vertices.rows());
  report.surface_area = surface.area;
  report.surface_mean_edge_length = surface.mean_edge_length;
  report.shells = static_cast<int>(surface.shells.size());
  report.check_seconds = Seconds(check_start);
  if (!status.ok()) {
    report.total_seconds = Seconds(start);
    return report.wrapped || !wrap_hint ? status : WithWrapHint(status);
  }
  int cavity_count = 0;
  for (const internal::SurfaceShell& shell : surface.shells) {
    const double volume = std::abs(shell.signed_volume);
    report.surface_volume += shell.depth % 2 == 0 ? volume : -volume;
    cavity_count += shell.depth % 2;
  }
  report.cavities = cavity_count;

  // Sizes.
  report.edge_length = options.edge_length > 0.0 ? options.edge_length : surface.mean_edge_length;
  // Delaunay refinement under a volume bound makes elements smaller than the bound: with the
  // regular tetrahedron's volume L^3 / (6 sqrt 2) the mean edge comes out at 0.87 L inside a
  // unit cube meshed with L = 0.05; 1.5 times that volume gives 0.97 L (0.89 L at L = 0.1,
  // where the faces weigh more).
  report.max_volume = std::pow(report.edge_length, 3) / (4.0 * std::sqrt(2.0));
  if (options.max_volume > 0.0) report.max_volume = std::min(report.max_volume, options.max_volume);
  report.radius_edge_ratio = options.radius_edge_ratio;
  report.min_dihedral_deg = options.min_dihedral_deg;
  const double at_least = report.surface_volume / report.max_volume;
  if (at_least > options.max_tets) {
    report.total_seconds = Seconds(start);
    return Status::Error(source + ": a largest tetrahedron volume of " + Fmt(report.max_volume) +
                         " (edge length " + Fmt(report.edge_length) + ") makes at least " +
                         Fmt(at_least) + " tetrahedra in a volume of " +
                         Fmt(report.surface_volume) +
                         ", more than the limit of " + std::to_string(options.max_tets) + " (max_tets)" +
                         ": choose a larger edge length or max volume, or, if the surface is not "
                         "in metres (a volume of " + Fmt(report.surface_volume) +
                         " m^3), --scale it (0.001 for millimetres)");
  }

  // Remesh to the target edge length; TetGen then keeps that surface.
  internal::CheckedSurface remeshed;
  const internal::CheckedSurface& tetgen_surface =
      options.remesh && options.edge_length > 0.0 && !options.keep_surface ? remeshed : surface;
  if (&tetgen_surface == &remeshed) {
    status = internal::RemeshCheckedSurface(surface, options, source, &remeshed, &report);
    if (!status.ok()) {
      report.total_seconds = Seconds(start);
      return status;
    }
  }
  std::vector<const internal::SurfaceShell*> solids, cavities;
  for (const internal::SurfaceShell& shell : tetgen_surface.shells) {
    (shell.depth % 2 == 0 ? solids : cavities).push_back(&shell);
  }
  const double used_volume = report.remeshed ? report.remeshed_volume : report.surface_volume;

  // TetGen's input: the points, one facet per triangle, a point per solid and per cavity.
  char switches[256];
  std::snprintf(switches, sizeof(switches), "pq%.10g/%.10ga%.10gM%s%s", options.radius_edge_ratio,
                options.min_dihedral_deg, report.max_volume, options.region_per_shell ? "A" : "",
                options.keep_surface || report.remeshed ? "Y" : "");
  report.tetgen_switches = switches;
  tetgenio in;
  const Vertices& W = tetgen_surface.vertices;
  const Triangles& T = tetgen_surface.triangles;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(W.rows());
  in.pointlist = new REAL[3 * static_cast<size_t>(W.rows())];
  std::copy(W.data(), W.data() + W.size(), in.pointlist);  // row-major: x y z per point
  in.numberoffacets = static_cast<int>(T.rows());
  in.facetlist = new tetgenio::facet[static_cast<size_t>(T.rows())];
  for (int t = 0; t < T.rows(); ++t) {
    tetgenio::facet& f = in.facetlist[t];
    tetgenio::init(&f);
    f.numberofpolygons = 1;
    f.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&f.polygonlist[0]);
    f.polygonlist[0].numberofvertices = 3;
    f.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k) f.polygonlist[0].vertexlist[k] = T(t, k);
  }
  if (!cavities.empty()) {
    in.numberofholes = static_cast<int>(cavities.size());
    in.holelist = new REAL[3 * cavities.size()];
    for (size_t h = 0; h < cavities.size(); ++h) {
      for (int k = 0; k < 3; ++k) in.holelist[3 * h + k] = cavities[h]->inside_point[k];
    }
  }
  if (options.region_per_shell) {
    in.numberofregions = static_cast<int>(solids.size());
    in.regionlist = new REAL[5 * solids.size()];
    for (size_t r = 0; r < solids.size(); ++r) {
      for (int k = 0; k < 3; ++k) in.regionlist[5 * r + k] = solids[r]->inside_point[k];
      in.regionlist[5 * r + 3] = static_cast<REAL>(r + 1);  // attribute: region id + 1
      in.regionlist[5 * r + 4] = -1.0;                      // no volume bound of its own
    }
  }

  const Clock::time_point tetgen_start = Clock::now();
  TetGenRun run;
  status = RunTetGen(report.tetgen_switches, &in, options.time_limit_seconds, &run);
  report.tetgen_seconds = Seconds(tetgen_start);
  report.tetgen_log = run.log;
  report.tetgen_warnings = Warnings(run.log);
  if (!status.ok()) {
    report.total_seconds = Seconds(start);
    return Status::Error(source + ": " + status.message());
  }
  if (run.outcome != TetGenRun::Outcome::kMesh || run.tets.empty()) {
    std::string message = source + ": ";
    switch (run.outcome) {
      case TetGenRun::Outcome::kTimedOut:
        message += "TetGen did not finish within " + Fmt(options.time_limit_seconds) +
                   " s (a larger edge length or quality ratio makes fewer elements)";
        break;
      case TetGenRun::Outcome::kGaveUp:
        message += TetGenFailure(run.code);
        break;
      case TetGenRun::Outcome::kCrashed:
        // TetGen 1.5.0 crashes while cleaning up after it gives up (see RunTetGen).
        message += "TetGen stopped without a mesh";
        if (run.signal != 0) {
          message += " (on signal " + std::to_string(run.signal) +
                     ": TetGen 1.5.0 crashes when it gives up)";
        }
        break;
      case TetGenRun::Outcome::kMesh:
        message += "TetGen made no tetrahedra";
        break;
    }
    const std::string stage = LastLine(run.log);
    if (!stage.empty()) message += "; its last words: '" + stage + "'";
    // Ask TetGen which triangles it finds crossing (its -d switch, within its own tolerance):
    // the most common reason it gives up on a surface that passed the checks.
    if (run.outcome != TetGenRun::Outcome::kTimedOut) {
      TetGenRun diagnosis;
      if (RunTetGen("pd", &in, options.time_limit_seconds, &diagnosis).ok()) {
        const std::string pairs = IntersectingPairs(diagnosis.log, T);
        if (!pairs.empty()) message += "; TetGen's -d finds " + pairs;
      }
    }
    report.total_seconds = Seconds(start);
    return Status::Error(message);
  }

  // TetGen's output as a femreg mesh, without vertices no element uses.
  const Clock::time_point finish_start = Clock::now();
  const int np = static_cast<int>(run.points.size() / 3),
            nt = static_cast<int>(run.tets.size() / 4);
  std::vector<int> index(static_cast<size_t>(np), -1);
  TetMesh result;
  result.tets.resize(nt, 4);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) {
      const int v = run.tets[4 * static_cast<size_t>(t) + k] - run.first_number;
      if (v < 0 || v >= np) {
        return Status::Error(source + ": TetGen's element " + std::to_string(t) +
                             " refers to point " + std::to_string(v) + " of " + std::to_string(np));
      }
      result.tets(t, k) = v;
      index[static_cast<size_t>(v)] = 0;
    }
  }
  int used = 0;
  for (int v = 0; v < np; ++v) {
    if (index[static_cast<size_t>(v)] == 0) index[static_cast<size_t>(v)] = used++;
  }
  result.rest.resize(used, 3);
  for (int v = 0; v < np; ++v) {
    const int i = index[static_cast<size_t>(v)];
    if (i >= 0) {
      for (int k = 0; k < 3; ++k) result.rest(i, k) = run.points[3 * static_cast<size_t>(v) + k];
    }
  }
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) result.tets(t, k) = index[static_cast<size_t>(result.tets(t, k))];
  }
  result.region = Eigen::VectorXi::Zero(nt);
  if (options.region_per_shell && run.num_attributes > 0) {
    for (int t = 0; t < nt; ++t) {
      const double attribute = run.attributes[static_cast<size_t>(run.num_attributes) * t];
      const long id = std::lround(attribute) - 1;
      if (id < 0 || id >= static_cast<long>(solids.size())) {
        return Status::Error(source + ": TetGen put element " + std::to_string(t) +
                             " in no region (attribute " + Fmt(attribute) + ")");
      }
      result.region(t) = static_cast<int>(id);
    }
  }
  // The elements along a curve through their centroids: TetGen's come in no spatial order, and
  // every loop over them (assembly, rotations, energies) then reads the vertices and writes
  // the matrix at scattered places (docs/notes/2026-11-30-element-order.md).
  {
    Vertices centroids(nt, 3);
    for (int t = 0; t < nt; ++t) {
      centroids.row(t) = 0.25 * (result.rest.row(result.tets(t, 0)) + result.rest.row(result.tets(t, 1)) +
                                 result.rest.row(result.tets(t, 2)) + result.rest.row(result.tets(t, 3)));
    }
    const std::vector<int> along = MortonOrder(centroids);
    Tets tets(nt, 4);
    Eigen::VectorXi region(nt);
    for (int t = 0; t < nt; ++t) {
      tets.row(t) = result.tets.row(along[static_cast<size_t>(t)]);
      region(t) = result.region(along[static_cast<size_t>(t)]);
    }
    result.tets = tets;
    result.region = region;
  }
  status = FinalizeMesh(&result, source + " (TetGen's mesh)");
  if (!status.ok()) return status;

  internal::MeasureMesh(result, &report);
  report.finish_seconds = Seconds(finish_start);
  report.total_seconds = Seconds(start);

  // The tetrahedra fill exactly the solid the surface bounds (TetGen splits triangles in
  // their plane, merges none, moves nothing; 1e-14 relative measured on the Bunny): a
  // different volume means a solid or a cavity was taken wrongly.
  if (std::abs(report.mesh_volume - used_volume) > 1e-9 * std::abs(used_volume)) {
    return Status::Error(source + ": TetGen's mesh has volume " + Fmt(report.mesh_volume) +
                         " but the surface it got encloses " + Fmt(used_volume));
  }
  *mesh = std::move(result);
  return Status::Ok();
}

}  // namespace internal
}  // namespace femreg
