// ReadTriangleSurface (femreg/io.h): OBJ and ASCII or binary STL in, and bad files refused
// naming the file and the line.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "femreg/io.h"
#include "test_util.h"

namespace femreg {
namespace {

using testing_util::TempDir;

TEST(ReadTriangleSurface, ReadsObjAndAsciiAndBinaryStl) {
  TempDir dir;
  Vertices v;
  Triangles t;
  dir.Write("quad.obj", "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 4/4\n");
  ASSERT_TRUE(ReadTriangleSurface(dir.File("quad.obj"), &v, &t).ok());
  EXPECT_EQ(v.rows(), 4);
  EXPECT_EQ(t.rows(), 2);
  dir.Write("neg.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n");
  ASSERT_TRUE(ReadTriangleSurface(dir.File("neg.OBJ"), &v, &t).ok());
  EXPECT_EQ(t.row(0), Eigen::RowVector3i(0, 1, 2));
  dir.Write("tri.stl",
            "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
            "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n"
            "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n");
  ASSERT_TRUE(ReadTriangleSurface(dir.File("tri.stl"), &v, &t).ok());
  EXPECT_EQ(v.rows(), 4);  // welded
  EXPECT_EQ(t.rows(), 2);
  std::string bin(80, '\0');
  const uint32_t n = 1;
  bin.append(reinterpret_cast<const char*>(&n), 4);
  const float rec[12] = {0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 2, 0};
  bin.append(reinterpret_cast<const char*>(rec), 48);
  bin.append(2, '\0');  // attribute byte count
  dir.Write("bin.stl", bin);
  ASSERT_TRUE(ReadTriangleSurface(dir.File("bin.stl"), &v, &t).ok());
  EXPECT_EQ(t.rows(), 1);
  EXPECT_EQ(v(1, 0), 2.0);
}

TEST(ReadTriangleSurface, ErrorsNameTheFileAndLine) {
  TempDir dir;
  Vertices v;
  Triangles t;
  auto message = [&](const std::string& name, const std::string& contents) {
    const Status s = ReadTriangleSurface(dir.Write(name, contents), &v, &t);
    EXPECT_FALSE(s.ok()) << name;
    return s.message();
  };
  EXPECT_EQ(message("bad.obj", "v 0 0 0\nf 1 2 3\n"), dir.File("bad.obj") + ":2: bad face index '2'");
  EXPECT_EQ(message("two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n"),
            dir.File("two.obj") + ":3: a face needs 3 vertices");
  EXPECT_EQ(message("none.obj", "v 0 0 0\n"), dir.File("none.obj") + ": no triangle");
  EXPECT_EQ(message("quad.stl", "solid q\nfacet\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
                                "vertex 0 1 0\nendfacet\n"),
            dir.File("quad.stl") + ": facet 0 has 4 vertices, not 3");
  EXPECT_NE(message("junk.stl", "not an stl").find("neither binary STL"), std::string::npos);
  EXPECT_EQ(message("s.ply", "ply\n"), dir.File("s.ply") + ": unknown surface format (expected .obj or .stl)");
  EXPECT_EQ(ReadTriangleSurface(dir.File("missing.obj"), &v, &t).message(),
            dir.File("missing.obj") + ": cannot open");
}

}  // namespace
}  // namespace femreg
