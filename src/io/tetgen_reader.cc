// TetGen .node + .ele: 0- or 1-based indices, optional region attribute.
#include <array>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Reads a header line of integers; `min_count` of them are required.
Status ReadHeader(TokenStream* in, int min_count, std::vector<long long>* values) {
  long long first;
  Status s = in->NextInt("the header", &first);
  if (!s.ok()) return s;
  values->assign(1, first);
  for (const Token& t : in->RestOfLine()) {
    long long v;
    if (!ParseInt(t.text, &v)) return in->Error("expected an integer in the header, found " + Quoted(t.text));
    values->push_back(v);
  }
  while (static_cast<int>(values->size()) < min_count) values->push_back(0);
  return Status::Ok();
}

}  // namespace

Status ReadTetGenFiles(const std::string& path, RawTetMesh* raw) {
  std::string base = path;
  if (EndsWith(path, ".node")) base = path.substr(0, path.size() - 5);
  if (EndsWith(path, ".ele")) base = path.substr(0, path.size() - 4);
  const std::string node_path = base + ".node", ele_path = base + ".ele";

  TokenStream nodes;
  Status s = nodes.Open(node_path, '#');
  if (!s.ok()) return s;
  std::vector<long long> header;
  if (!(s = ReadHeader(&nodes, 4, &header)).ok()) return s;
  const long long num_points = header[0];
  if (header[1] != 3) return nodes.Error("only 3-dimensional .node files are supported");
  if (num_points <= 0) return nodes.Error("no points");
  // Attributes and boundary markers per point: a line holds at most what the file holds.
  if (header[2] < 0 || header[2] > MaxItemsIn(nodes.remaining(), 1)) {
    return nodes.Error("the number of point attributes is " + std::to_string(header[2]) +
                       ", negative or more than the file holds");
  }
  const long long num_values = 3 + header[2] + (header[3] != 0 ? 1 : 0);
  std::unordered_map<long long, int> index;
  for (long long i = 0; i < num_points; ++i) {
    long long id;
    if (!(s = nodes.NextInt("a point index", &id)).ok()) return s;
    const int line = nodes.line();
    std::vector<Token> rest = nodes.RestOfLine();
    if (static_cast<long long>(rest.size()) < num_values) {
      return nodes.ErrorAt(line, "truncated point line (expected x y z and the attributes)");
    }
    std::array<double, 3> xyz;
    for (int k = 0; k < 3; ++k) {
      if (!ParseDouble(rest[k].text, &xyz[k])) {
        return nodes.ErrorAt(line, "expected a coordinate, found " + Quoted(rest[k].text));
      }
      if (!std::isfinite(xyz[k])) {
        std::ostringstream os;
        os << "point " << id << " has a non-finite coordinate";
        return nodes.ErrorAt(line, os.str());
      }
    }
    if (!index.emplace(id, static_cast<int>(raw->vertices.size())).second) {
      std::ostringstream os;
      os << "point " << id << " is defined twice";
      return nodes.ErrorAt(line, os.str());
    }
    raw->vertices.push_back(xyz);
  }

  TokenStream eles;
  if (!(s = eles.Open(ele_path, '#')).ok()) return s;
  if (!(s = ReadHeader(&eles, 3, &header)).ok()) return s;
  const long long num_tets = header[0], nodes_per_tet = header[1], num_attributes = header[2];
  if (nodes_per_tet != 4 && nodes_per_tet != 10) {
    return eles.Error("nodes per tetrahedron must be 4 or 10");
  }
  if (num_attributes < 0 || num_attributes > MaxItemsIn(eles.remaining(), 1)) {
    return eles.Error("the number of element attributes is " + std::to_string(num_attributes) +
                      ", negative or more than the file holds");
  }

  for (long long i = 0; i < num_tets; ++i) {
    long long id;
    if (!(s = eles.NextInt("an element index", &id)).ok()) return s;
    const int line = eles.line();
    std::vector<Token> rest = eles.RestOfLine();
    if (static_cast<long long>(rest.size()) < nodes_per_tet + num_attributes) {
      return eles.ErrorAt(line, "truncated element line");
    }
    std::array<int, 4> tet;
    for (int k = 0; k < 4; ++k) {
      long long v;
      if (!ParseInt(rest[k].text, &v)) {
        return eles.ErrorAt(line, "expected a point index, found " + Quoted(rest[k].text));
      }
      auto it = index.find(v);
      if (it == index.end()) {
        std::ostringstream os;
        os << "element " << id << " refers to point " << v << ", which " << node_path
           << " does not define (index out of range)";
        return eles.ErrorAt(line, os.str());
      }
      tet[k] = it->second;
    }
    int region = 0;
    if (num_attributes > 0) {
      double attribute;
      if (!ParseDouble(rest[nodes_per_tet].text, &attribute) || !RegionIdFrom(attribute, &region)) {
        return eles.ErrorAt(line, "expected a region attribute (an integer in the range of int), found " +
                                      Quoted(rest[nodes_per_tet].text));
      }
    }
    raw->tets.push_back(tet);
    raw->regions.push_back(region);
    raw->tet_lines.push_back(line);
  }
  raw->lines_file = ele_path;  // line numbers in later messages refer to the .ele file
  return Status::Ok();
}

}  // namespace internal
}  // namespace femreg
