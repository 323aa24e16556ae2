// femreg's own VTU reader (src/io/vtu_reader.cc): files written by VTK's
// vtkXMLUnstructuredGridWriter in every data mode, encoding, header type, byte order and
// compression read back exactly; malformed files refused with the byte offset of the problem.
#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <fstream>
#include <iterator>
#include <string>

#include "femreg/eval.h"
#include "femreg/io.h"
#include "io/io_internal.h"
#include "test_util.h"

namespace femreg {
namespace {

using internal::VtuArray;
using internal::VtuGrid;
using internal::VtuPiece;

using testing_util::TempDir;

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// What the test writes: a 3x2x2-cell box of tetrahedra plus one triangle (a cell femreg's
// mesh reader skips), a region per cell, a 3-component point field and original_vertex.
struct Expected {
  TetMesh box = MakeBox(Eigen::Vector3d(1.0, 2.0, 0.5), 3, 2, 2);
  std::vector<int> region;
  std::vector<double> displacement;  // #V x 3
};

enum Mode { kAscii, kBinary, kAppendedRaw, kAppendedBase64 };

struct WriteCase {
  const char* name;
  Mode mode;
  bool zlib;
  bool uint64_header;
  bool big_endian;
  bool float32_points;
};

std::string WriteWithVtk(const std::string& path, const WriteCase& c, Expected* e) {
  const TetMesh& box = e->box;
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> points;
  if (c.float32_points) {
    points->SetDataTypeToFloat();
  } else {
    points->SetDataTypeToDouble();
  }
  points->SetNumberOfPoints(box.num_vertices());
  for (int v = 0; v < box.num_vertices(); ++v) {
    // Values that are not round in binary, to catch a lost bit.
    points->SetPoint(v, box.rest(v, 0) + 0.1, box.rest(v, 1) / 3.0, box.rest(v, 2) - 1e-7);
  }
  grid->SetPoints(points);
  grid->Allocate(box.num_tets() + 1);
  for (int t = 0; t < box.num_tets(); ++t) {
    const vtkIdType ids[4] = {box.tets(t, 0), box.tets(t, 1), box.tets(t, 2), box.tets(t, 3)};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  const vtkIdType tri[3] = {0, 1, 2};
  grid->InsertNextCell(VTK_TRIANGLE, 3, tri);
  vtkNew<vtkIntArray> region;
  region->SetName("region");
  region->SetNumberOfTuples(box.num_tets() + 1);
  e->region.clear();
  for (int t = 0; t <= box.num_tets(); ++t) {
    region->SetValue(t, 3 * t - 7);
    e->region.push_back(3 * t - 7);
  }
  grid->GetCellData()->AddArray(region);
  vtkNew<vtkDoubleArray> displacement;
  displacement->SetName("displacement");
  displacement->SetNumberOfComponents(3);
  displacement->SetNumberOfTuples(box.num_vertices());
  e->displacement.clear();
  for (int v = 0; v < box.num_vertices(); ++v) {
    for (int k = 0; k < 3; ++k) {
      const double value = std::sin(1.0 + v * 3 + k) * 1e-3;
      displacement->SetComponent(v, k, value);
      e->displacement.push_back(value);
    }
  }
  grid->GetPointData()->AddArray(displacement);
  vtkNew<vtkIntArray> original;
  original->SetName("original_vertex");
  original->SetNumberOfTuples(box.num_vertices());
  for (int v = 0; v < box.num_vertices(); ++v) original->SetValue(v, 1000 + v);
  grid->GetPointData()->AddArray(original);

  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(grid);
  switch (c.mode) {
    case kAscii: writer->SetDataModeToAscii(); break;
    case kBinary: writer->SetDataModeToBinary(); break;
    case kAppendedRaw:
      writer->SetDataModeToAppended();
      writer->EncodeAppendedDataOff();
      break;
    case kAppendedBase64:
      writer->SetDataModeToAppended();
      writer->EncodeAppendedDataOn();
      break;
  }
  if (c.zlib) {
    writer->SetCompressorTypeToZLib();
    writer->SetBlockSize(256);  // several blocks per array, and a short last one
  } else {
    writer->SetCompressorTypeToNone();
  }
  if (c.uint64_header) {
    writer->SetHeaderTypeToUInt64();
  } else {
    writer->SetHeaderTypeToUInt32();
  }
  if (c.big_endian) {
    writer->SetByteOrderToBigEndian();
  } else {
    writer->SetByteOrderToLittleEndian();
  }
  EXPECT_EQ(writer->Write(), 1);
  return ReadBytes(path);
}

void PrintTo(const WriteCase& c, std::ostream* os) { *os << c.name; }

class VtuRoundTrip : public ::testing::TestWithParam<WriteCase> {};

TEST_P(VtuRoundTrip, ReadsBackWhatVtkWrote) {
  const WriteCase& c = GetParam();
  TempDir dir;
  const std::string path = dir.File("grid.vtu");
  Expected e;
  const std::string text = WriteWithVtk(path, c, &e);
  // The file is what the case asks for.
  EXPECT_EQ(text.find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos, c.zlib);
  EXPECT_EQ(text.find("header_type=\"UInt64\"") != std::string::npos, c.uint64_header);
  EXPECT_EQ(text.find("BigEndian") != std::string::npos, c.big_endian);
  const char* format = c.mode == kAscii ? "format=\"ascii\"" : c.mode == kBinary ? "format=\"binary\"" : "format=\"appended\"";
  EXPECT_NE(text.find(format), std::string::npos);
  if (c.mode == kAppendedRaw) {
    EXPECT_NE(text.find("encoding=\"raw\""), std::string::npos);
  }
  if (c.mode == kAppendedBase64) {
    EXPECT_NE(text.find("encoding=\"base64\""), std::string::npos);
  }

  VtuGrid grid;
  const Status status = internal::ReadVtuGrid(path, &grid);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(grid.pieces.size(), 1u);
  const VtuPiece& piece = grid.pieces[0];
  const TetMesh& box = e.box;
  ASSERT_EQ(static_cast<int>(piece.points.size()), box.num_vertices());
  for (int v = 0; v < box.num_vertices(); ++v) {
    const double want[3] = {box.rest(v, 0) + 0.1, box.rest(v, 1) / 3.0, box.rest(v, 2) - 1e-7};
    for (int k = 0; k < 3; ++k) {
      // ascii Float64 is written with 17 digits: exact; Float32 exact to a float.
      const double expected = c.float32_points ? static_cast<double>(static_cast<float>(want[k])) : want[k];
      ASSERT_EQ(piece.points[static_cast<size_t>(v)][k], expected) << "point " << v;
    }
  }
  ASSERT_EQ(static_cast<int>(piece.types.size()), box.num_tets() + 1);
  ASSERT_EQ(piece.offsets.size(), piece.types.size() + 1);
  for (int t = 0; t < box.num_tets(); ++t) {
    ASSERT_EQ(piece.types[static_cast<size_t>(t)], VTK_TETRA);
    ASSERT_EQ(piece.offsets[static_cast<size_t>(t)], 4 * t);
    for (int k = 0; k < 4; ++k) {
      ASSERT_EQ(piece.connectivity[static_cast<size_t>(4 * t + k)], box.tets(t, k)) << "tet " << t;
    }
  }
  EXPECT_EQ(piece.types.back(), VTK_TRIANGLE);
  EXPECT_EQ(piece.offsets.back(), 4 * box.num_tets() + 3);
  ASSERT_EQ(piece.cell_data.size(), 1u);
  EXPECT_EQ(piece.cell_data[0].name, "region");
  ASSERT_EQ(piece.cell_data[0].values.size(), e.region.size());
  for (size_t t = 0; t < e.region.size(); ++t) EXPECT_EQ(piece.cell_data[0].values[t], e.region[t]);
  ASSERT_EQ(piece.point_data.size(), 2u);
  const VtuArray& displacement = piece.point_data[0];
  EXPECT_EQ(displacement.name, "displacement");
  EXPECT_EQ(displacement.components, 3);
  ASSERT_EQ(displacement.values.size(), e.displacement.size());
  for (size_t i = 0; i < e.displacement.size(); ++i) {
    if (c.mode == kAscii) {
      EXPECT_NEAR(displacement.values[i], e.displacement[i], 1e-15);
    } else {
      EXPECT_EQ(displacement.values[i], e.displacement[i]);
    }
  }

  // As a mesh: the tetrahedra and their regions, the triangle skipped.
  TetMesh mesh;
  const Status read = ReadTetMesh(path, &mesh);
  ASSERT_TRUE(read.ok()) << read.message();
  EXPECT_EQ(mesh.num_vertices(), box.num_vertices());
  ASSERT_EQ(mesh.num_tets(), box.num_tets());
  for (int t = 0; t < box.num_tets(); ++t) EXPECT_EQ(mesh.region(t), e.region[static_cast<size_t>(t)]);

  // As geometry: the triangle and the boundary of the tetrahedra, original_vertex.
  VtuGeometry geometry;
  const Status g = ReadVtuGeometry(path, &geometry);
  ASSERT_TRUE(g.ok()) << g.message();
  EXPECT_EQ(geometry.points.rows(), box.num_vertices());
  EXPECT_EQ(geometry.tets.rows(), box.num_tets());
  EXPECT_EQ(geometry.surface.row(0), Eigen::RowVector3i(0, 1, 2));
  ASSERT_EQ(static_cast<int>(geometry.original.size()), box.num_vertices());
  EXPECT_EQ(geometry.original.back(), 1000 + box.num_vertices() - 1);
}

INSTANTIATE_TEST_SUITE_P(
    AllModes, VtuRoundTrip,
    ::testing::Values(WriteCase{"Ascii", kAscii, false, false, false, false},
                      WriteCase{"AsciiFloat32", kAscii, false, true, false, true},
                      WriteCase{"Binary", kBinary, false, false, false, false},
                      WriteCase{"BinaryUInt64", kBinary, false, true, false, true},
                      WriteCase{"BinaryZlib", kBinary, true, false, false, false},
                      WriteCase{"BinaryZlibUInt64BigEndian", kBinary, true, true, true, false},
                      WriteCase{"AppendedRaw", kAppendedRaw, false, false, false, false},
                      WriteCase{"AppendedRawUInt64BigEndian", kAppendedRaw, false, true, true, true},
                      WriteCase{"AppendedRawZlib", kAppendedRaw, true, false, false, true},
                      WriteCase{"AppendedRawZlibUInt64", kAppendedRaw, true, true, false, false},
                      WriteCase{"AppendedBase64", kAppendedBase64, false, false, false, false},
                      WriteCase{"AppendedBase64UInt64", kAppendedBase64, false, true, false, false},
                      WriteCase{"AppendedBase64Zlib", kAppendedBase64, true, false, false, false},
                      WriteCase{"AppendedBase64ZlibUInt64BigEndian", kAppendedBase64, true, true, true, true}),
    [](const ::testing::TestParamInfo<WriteCase>& info) { return std::string(info.param.name); });

// Two pieces are concatenated, the second one's point indices shifted.
TEST(VtuReader, TwoPiecesAreConcatenated) {
  TempDir dir;
  const std::string piece =
      "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\"><Points>"
      "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1</DataArray>"
      "</Points><Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>"
      "<CellData><DataArray type=\"Int32\" Name=\"tag\" format=\"ascii\">REGION</DataArray></CellData></Piece>";
  std::string first = piece, second = piece;
  first.replace(first.find("REGION"), 6, "4");
  second.replace(second.find("REGION"), 6, "9");
  second.replace(second.find("0 0 0 1 0 0"), 11, "5 0 0 6 0 0");
  const std::string path = dir.Write("two.vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">"
                                                "<UnstructuredGrid>" + first + second + "</UnstructuredGrid></VTKFile>\n");
  TetMesh mesh;
  const Status status = ReadTetMesh(path, &mesh);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(mesh.num_vertices(), 8);
  ASSERT_EQ(mesh.num_tets(), 2);
  EXPECT_EQ(mesh.region(0), 4);
  EXPECT_EQ(mesh.region(1), 9);
  EXPECT_EQ(mesh.rest(mesh.tets(1, 0), 0), 5.0);

  // Piece 0's tetrahedron pointing at point 4: in the file, the first point of piece 1; in
  // piece 0, out of range. Refused, not read as the other piece's point.
  std::string stray = first;
  stray.replace(stray.find("0 1 2 3"), 7, "0 1 2 4");
  Status s = ReadTetMesh(dir.Write("stray.vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">"
                                                "<UnstructuredGrid>" + stray + second + "</UnstructuredGrid></VTKFile>\n"),
                         &mesh);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("cell 0 refers to point -1"), std::string::npos) << s.message();
  // A piece without piece 0's region array.
  std::string untagged = second;
  untagged.erase(untagged.find("<CellData>"), untagged.find("</CellData>") + 11 - untagged.find("<CellData>"));
  s = ReadTetMesh(dir.Write("untagged.vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">"
                                            "<UnstructuredGrid>" + first + untagged + "</UnstructuredGrid></VTKFile>\n"),
                  &mesh);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("has no cell array 'tag'"), std::string::npos) << s.message();
}

// Malformed files: refused with the byte offset of the problem, before anything is sized
// from the bad number.
struct Malformed {
  const char* name;
  std::string text;
  std::string at;        // the problem is at the first occurrence of this text in the file
  std::string expected;  // in the message after "byte N: "
};

std::string AsciiFile(const std::string& points_attrs, const std::string& points, const std::string& offsets) {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
         "<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"2\">\n<Points>"
         "<DataArray type=\"Float32\" NumberOfComponents=\"3\" " + points_attrs + ">" + points + "</DataArray></Points>\n"
         "<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3 0 1 2</DataArray>\n"
         "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">" + offsets + "</DataArray>\n"
         "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10 5</DataArray></Cells>\n"
         "</Piece></UnstructuredGrid></VTKFile>\n";
}

void PrintTo(const Malformed& m, std::ostream* os) { *os << m.name; }

class VtuMalformed : public ::testing::TestWithParam<Malformed> {};

TEST_P(VtuMalformed, IsRefusedAtItsByteOffset) {
  const Malformed& m = GetParam();
  TempDir dir;
  const std::string path = dir.Write("bad.vtu", m.text);
  const size_t at = m.text.find(m.at);
  ASSERT_NE(at, std::string::npos);
  TetMesh mesh;
  const Status status = ReadTetMesh(path, &mesh);
  ASSERT_FALSE(status.ok());
  const std::string expected = path + ": byte " + std::to_string(at) + ": " + m.expected;
  EXPECT_EQ(status.message().substr(0, expected.size()), expected) << status.message();
  VtuGeometry geometry;
  EXPECT_FALSE(ReadVtuGeometry(path, &geometry).ok());
}

const std::string kPoints = "0 0 0 1 0 0 0 1 0 0 0 1";
// "AAAAAA==" is a 4-byte count of 0; base64 of 48 zero bytes is 64 'A's.
const std::string kBinaryPoints = "MAAAAA==" + std::string(64, 'A');

INSTANTIATE_TEST_SUITE_P(
    Cases, VtuMalformed,
    ::testing::Values(
        Malformed{"OffsetsGoBack", AsciiFile("format=\"ascii\"", kPoints, "4 3"), "<DataArray type=\"Int32\" Name=\"offsets\"",
                  "piece 0: cell 1 ends at offset 3, not an integer from 4 (where it starts) to 2147483647"},
        Malformed{"ConnectivityShorterThanOffsets", AsciiFile("format=\"ascii\"", kPoints, "4 9"),
                  "<DataArray type=\"Int32\" Name=\"connectivity\"", "ascii DataArray 'connectivity' needs 9 values"},
        Malformed{"NotBase64", AsciiFile("format=\"binary\"", "MAAAAA==" + std::string(20, 'A') + "*" + std::string(43, 'A'), "4 7"),
                  "*", "binary DataArray '': '*' is not base64"},
        Malformed{"ByteCountPastTheBase64", AsciiFile("format=\"binary\"", "//8AAA==" + std::string(64, 'A'), "4 7"),
                  "//8AAA==", "binary DataArray '': says 65535 bytes, 48 are left"},
        Malformed{"ByteCountBelowTheCounts", AsciiFile("format=\"binary\"", "LAAAAA==" + std::string(64, 'A'), "4 7"),
                  "LAAAAA==", "binary DataArray '': holds 44 bytes, the header's counts need 48"},
        Malformed{"Lz4Compressor",
                  "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkLZ4DataCompressor\"><UnstructuredGrid/></VTKFile>",
                  "<VTKFile", "VTKFile compressor='vtkLZ4DataCompressor' is not supported (only vtkZLibDataCompressor)"}),
    [](const ::testing::TestParamInfo<Malformed>& info) { return std::string(info.param.name); });

// A raw appended array whose byte count runs past the file, and a zlib block that is not
// zlib data, in files VTK wrote.
TEST(VtuReader, CorruptAppendedDataIsRefusedAtItsOffset) {
  TempDir dir;
  Expected e;
  const std::string raw = WriteWithVtk(dir.File("raw.vtu"), {"", kAppendedRaw, false, false, false, false}, &e);
  const size_t marker = raw.find('_', raw.find("<AppendedData"));
  ASSERT_NE(marker, std::string::npos);
  std::string cut = raw;
  cut[marker + 1] = '\xff';  // the first array's byte count: now 255 + what it was
  cut[marker + 2] = '\xff';
  cut[marker + 3] = '\xff';
  cut[marker + 4] = '\x7f';
  VtuGrid grid;
  Status status = internal::ReadVtuGrid(dir.Write("count.vtu", cut), &grid);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find(": byte " + std::to_string(marker + 1) + ": appended DataArray"), std::string::npos)
      << status.message();
  EXPECT_NE(status.message().find("says 2147483647 bytes"), std::string::npos) << status.message();

  const std::string zlib = WriteWithVtk(dir.File("zlib.vtu"), {"", kAppendedRaw, true, false, false, false}, &e);
  const size_t data = zlib.find('_', zlib.find("<AppendedData")) + 1;
  // The first array's header: 3 words and one size per block; its first block follows.
  auto word = [&](size_t at) {
    return static_cast<uint32_t>(static_cast<unsigned char>(zlib[at])) |
           static_cast<uint32_t>(static_cast<unsigned char>(zlib[at + 1])) << 8 |
           static_cast<uint32_t>(static_cast<unsigned char>(zlib[at + 2])) << 16 |
           static_cast<uint32_t>(static_cast<unsigned char>(zlib[at + 3])) << 24;
  };
  const size_t first_block = data + 12 + 4 * word(data);
  std::string corrupt = zlib;
  for (size_t i = 0; i < 8; ++i) corrupt[first_block + i] = 'x';
  status = internal::ReadVtuGrid(dir.Write("corrupt.vtu", corrupt), &grid);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find(": byte " + std::to_string(first_block) + ": appended DataArray"), std::string::npos)
      << status.message();
  EXPECT_NE(status.message().find("block 0 does not decompress"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace femreg
