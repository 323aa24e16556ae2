// Gmsh MSH 1 ($NOD/$ELM), 2.2 and 4.1 ASCII. Tetrahedra (type 4) are kept, other cells
// skipped; the physical tag becomes the region id.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <unordered_map>

#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {
namespace {

constexpr int kGmshTet = 4;

class GmshReader {
 public:
  GmshReader(TokenStream* in, RawTetMesh* raw) : in_(*in), raw_(*raw) {}

  Status Read() {
    Token t;
    bool saw_nodes = false, saw_elements = false;
    while (in_.Next(&t)) {
      const std::string& s = t.text;
      Status status;
      if (s == "$MeshFormat") {
        status = ReadMeshFormat();
      } else if (s == "$NOD" || s == "$NOE") {
        version_ = 1;
        status = ReadNodesV12("$ENDNOD");
        saw_nodes = true;
      } else if (s == "$Nodes") {
        status = version_ >= 4 ? ReadNodesV4() : ReadNodesV12("$EndNodes");
        saw_nodes = true;
      } else if (s == "$ELM") {
        version_ = 1;
        status = ReadElementsV12("$ENDELM");
        saw_elements = true;
      } else if (s == "$Elements") {
        status = version_ >= 4 ? ReadElementsV4() : ReadElementsV12("$EndElements");
        saw_elements = true;
      } else if (s == "$Entities") {
        status = ReadEntities();
      } else if (!s.empty() && s[0] == '$') {
        status = SkipSection(s);
      } else {
        return in_.Error("unexpected " + Quoted(s) + " outside of a section");
      }
      if (!status.ok()) return status;
    }
    if (!saw_nodes) return in_.Error("no $Nodes section (truncated file?)");
    if (!saw_elements) return in_.Error("no $Elements section (truncated file?)");
    return Status::Ok();
  }

 private:
  Status ReadMeshFormat() {
    std::string version;
    Status s = in_.NextWord("the format version", &version);
    if (!s.ok()) return s;
    long long file_type, data_size;
    if (!(s = in_.NextInt("the file type", &file_type)).ok()) return s;
    if (!(s = in_.NextInt("the data size", &data_size)).ok()) return s;
    if (file_type != 0) return in_.Error("binary MSH files are not supported (save as ASCII)");
    if (version.rfind("2", 0) == 0) {
      version_ = 2;
    } else if (version.rfind("4", 0) == 0) {
      version_ = 4;
      if (version != "4.1") return in_.Error("MSH version " + Quoted(version) + " is not supported (use 4.1)");
    } else {
      return in_.Error("MSH version " + Quoted(version) + " is not supported (1, 2.2 and 4.1 are)");
    }
    return Expect("$EndMeshFormat");
  }

  Status Expect(const std::string& word) {
    Token t;
    if (!in_.Next(&t)) return in_.Error("unexpected end of file, expected " + word);
    if (t.text != word) return in_.Error("expected " + word + ", found " + Quoted(t.text));
    return Status::Ok();
  }

  Status SkipSection(const std::string& name) {
    const std::string end = "$End" + name.substr(1);
    const std::string end_upper = "$END" + name.substr(1);
    Token t;
    while (in_.Next(&t)) {
      if (t.text == end || t.text == end_upper) return Status::Ok();
    }
    return in_.Error("unexpected end of file in section " + name);
  }

  Status AddNode(long long tag, int line) {
    double xyz[3];
    for (int k = 0; k < 3; ++k) {
      Status s = in_.NextDouble("a node coordinate", &xyz[k]);
      if (!s.ok()) return s;
      if (!std::isfinite(xyz[k])) {
        std::ostringstream os;
        os << "node " << tag << " has a non-finite coordinate";
        return in_.ErrorAt(line, os.str());
      }
    }
    if (!node_index_.emplace(tag, static_cast<int>(raw_.vertices.size())).second) {
      std::ostringstream os;
      os << "node " << tag << " is defined twice";
      return in_.ErrorAt(line, os.str());
    }
    raw_.vertices.push_back({xyz[0], xyz[1], xyz[2]});
    return Status::Ok();
  }

  Status ReadNodesV12(const char* end) {
    long long n;
    Status s = in_.NextInt("the number of nodes", &n);
    if (!s.ok()) return s;
    if (n < 0) return in_.Error("negative number of nodes");
    for (long long i = 0; i < n; ++i) {
      long long tag;
      if (!(s = in_.NextInt("a node number", &tag)).ok()) return s;
      if (!(s = AddNode(tag, in_.line())).ok()) return s;
    }
    return Expect(end);
  }

  Status ReadNodesV4() {
    long long blocks, n, min_tag, max_tag;
    Status s;
    if (!(s = in_.NextInt("the number of node blocks", &blocks)).ok()) return s;
    if (!(s = in_.NextInt("the number of nodes", &n)).ok()) return s;
    if (!(s = in_.NextInt("the minimum node tag", &min_tag)).ok()) return s;
    if (!(s = in_.NextInt("the maximum node tag", &max_tag)).ok()) return s;
    for (long long b = 0; b < blocks; ++b) {
      long long dim, entity, parametric, count;
      if (!(s = in_.NextInt("the entity dimension", &dim)).ok()) return s;
      if (!(s = in_.NextInt("the entity tag", &entity)).ok()) return s;
      if (!(s = in_.NextInt("the parametric flag", &parametric)).ok()) return s;
      if (!(s = in_.NextInt("the number of nodes in the block", &count)).ok()) return s;
      // Each node takes its tag and 3 coordinates.
      if (!(s = in_.CheckCount("the number of nodes in the block", count, 4)).ok()) return s;
      std::vector<long long> tags(static_cast<size_t>(count));
      for (auto& tag : tags) {
        if (!(s = in_.NextInt("a node tag", &tag)).ok()) return s;
      }
      for (long long tag : tags) {
        Token peek;
        const int line = in_.Peek(&peek) ? peek.line : in_.line();
        if (!(s = AddNode(tag, line)).ok()) return s;
        if (parametric) {
          for (long long k = 0; k < dim; ++k) {
            double u;
            if (!(s = in_.NextDouble("a parametric coordinate", &u)).ok()) return s;
          }
        }
      }
    }
    return Expect("$EndNodes");
  }

  Status ReadEntities() {
    long long counts[4];
    Status s;
    for (auto& c : counts) {
      if (!(s = in_.NextInt("the number of entities", &c)).ok()) return s;
    }
    for (int dim = 0; dim < 4; ++dim) {
      for (long long e = 0; e < counts[dim]; ++e) {
        long long tag;
        double v;
        if (!(s = in_.NextInt("an entity tag", &tag)).ok()) return s;
        const int num_coords = dim == 0 ? 3 : 6;
        for (int k = 0; k < num_coords; ++k) {
          if (!(s = in_.NextDouble("an entity bounding box", &v)).ok()) return s;
        }
        long long num_physical;
        if (!(s = in_.NextInt("the number of physical tags", &num_physical)).ok()) return s;
        for (long long k = 0; k < num_physical; ++k) {
          long long physical;
          if (!(s = in_.NextInt("a physical tag", &physical)).ok()) return s;
          if (k == 0 && dim == 3) volume_physical_[tag] = static_cast<int>(physical);
        }
        if (dim > 0) {
          long long num_bounding, bounding;
          if (!(s = in_.NextInt("the number of bounding entities", &num_bounding)).ok()) return s;
          for (long long k = 0; k < num_bounding; ++k) {
            if (!(s = in_.NextInt("a bounding entity", &bounding)).ok()) return s;
          }
        }
      }
    }
    return Expect("$EndEntities");
  }

  // Looks the node tags of a tetrahedron up and appends it.
  Status AddTet(const std::vector<Token>& nodes, int region, int line) {
    std::array<int, 4> tet;
    for (int k = 0; k < 4; ++k) {
      long long tag;
      if (!ParseInt(nodes[k].text, &tag)) {
        return in_.ErrorAt(line, "expected a node number, found " + Quoted(nodes[k].text));
      }
      auto it = node_index_.find(tag);
      if (it == node_index_.end()) {
        std::ostringstream os;
        os << "element refers to node " << tag << ", which is not defined (index out of range)";
        return in_.ErrorAt(line, os.str());
      }
      tet[k] = it->second;
    }
    raw_.tets.push_back(tet);
    raw_.regions.push_back(region);
    raw_.tet_lines.push_back(line);
    return Status::Ok();
  }

  Status ReadElementsV12(const char* end) {
    long long n;
    Status s = in_.NextInt("the number of elements", &n);
    if (!s.ok()) return s;
    for (long long i = 0; i < n; ++i) {
      long long number;
      if (!(s = in_.NextInt("an element number", &number)).ok()) return s;
      const int line = in_.line();
      std::vector<Token> rest = in_.RestOfLine();
      std::vector<long long> ints;
      for (const Token& tok : rest) {
        long long v;
        if (!ParseInt(tok.text, &v)) {
          return in_.ErrorAt(line, "expected an integer in the element, found " + Quoted(tok.text));
        }
        ints.push_back(v);
      }
      // v1: type phys elementary num_nodes nodes...; v2: type num_tags tags... nodes...
      size_t first_node;
      int region = 0;
      if (ints.size() < 2) return in_.ErrorAt(line, "truncated element line");
      const long long type = ints[0];
      if (version_ == 1) {
        if (ints.size() < 4) return in_.ErrorAt(line, "truncated element line");
        region = static_cast<int>(ints[1]);
        first_node = 4;
        if (ints.size() != 4 + static_cast<size_t>(ints[3])) {
          return in_.ErrorAt(line, "element line does not have the number of nodes it announces");
        }
      } else {
        const long long num_tags = ints[1];
        if (num_tags < 0 || ints.size() < 2 + static_cast<size_t>(num_tags)) {
          return in_.ErrorAt(line, "truncated element line");
        }
        if (num_tags > 0) region = static_cast<int>(ints[2]);
        first_node = 2 + static_cast<size_t>(num_tags);
      }
      if (type != kGmshTet) continue;
      if (rest.size() != first_node + 4) {
        return in_.ErrorAt(line, "a tetrahedron needs 4 nodes");
      }
      if (!(s = AddTet(std::vector<Token>(rest.begin() + first_node, rest.end()), region, line)).ok())
        return s;
    }
    return Expect(end);
  }

  Status ReadElementsV4() {
    long long blocks, n, min_tag, max_tag;
    Status s;
    if (!(s = in_.NextInt("the number of element blocks", &blocks)).ok()) return s;
    if (!(s = in_.NextInt("the number of elements", &n)).ok()) return s;
    if (!(s = in_.NextInt("the minimum element tag", &min_tag)).ok()) return s;
    if (!(s = in_.NextInt("the maximum element tag", &max_tag)).ok()) return s;
    for (long long b = 0; b < blocks; ++b) {
      long long dim, entity, type, count;
      if (!(s = in_.NextInt("the entity dimension", &dim)).ok()) return s;
      if (!(s = in_.NextInt("the entity tag", &entity)).ok()) return s;
      if (!(s = in_.NextInt("the element type", &type)).ok()) return s;
      if (!(s = in_.NextInt("the number of elements in the block", &count)).ok()) return s;
      int region = 0;
      auto it = volume_physical_.find(entity);
      if (dim == 3 && it != volume_physical_.end()) region = it->second;
      for (long long i = 0; i < count; ++i) {
        long long tag;
        if (!(s = in_.NextInt("an element tag", &tag)).ok()) return s;
        const int line = in_.line();
        std::vector<Token> nodes = in_.RestOfLine();
        if (type != kGmshTet) continue;
        if (nodes.size() != 4) return in_.ErrorAt(line, "a tetrahedron needs 4 nodes");
        if (!(s = AddTet(nodes, region, line)).ok()) return s;
      }
    }
    return Expect("$EndElements");
  }

  TokenStream& in_;
  RawTetMesh& raw_;
  int version_ = 1;
  std::unordered_map<long long, int> node_index_;
  std::map<long long, int> volume_physical_;  // volume entity tag -> first physical tag
};

}  // namespace

Status ReadGmshFile(const std::string& path, RawTetMesh* raw) {
  TokenStream in;
  Status s = in.Open(path, '\0');
  if (!s.ok()) return s;
  return GmshReader(&in, raw).Read();
}

}  // namespace internal
}  // namespace femreg
