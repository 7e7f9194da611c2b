#include <gtest/gtest.h>

#include <cmath>

#include "model/make_pipe.hpp"
#include "model/pipe_model.hpp"
#include "model/stl.hpp"
#include "test_util.hpp"

namespace pipeloc {
namespace {

using test::TempDir;

Mesh small_pipe() {
  PipeSpec spec;
  spec.diameter_mm = 12;
  spec.sides = 12;
  spec.segments = parse_centreline("S30,B90r20,S20");
  return make_pipe(spec);
}

void expect_same_mesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.faces.size(), b.faces.size());
  for (std::size_t f = 0; f < a.faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_LT((a.vertices[a.faces[f][k]] - b.vertices[b.faces[f][k]]).norm(), 1e-4f) << "face " << f;
}

std::string error_of(const std::string& path) {
  try {
    read_stl(path);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

TEST(Stl, BinaryRoundTrip) {
  TempDir dir;
  const Mesh mesh = small_pipe();
  write_stl(dir.file("p.stl"), mesh, StlFormat::binary);
  expect_same_mesh(mesh, read_stl(dir.file("p.stl")));
}

TEST(Stl, AsciiRoundTrip) {
  TempDir dir;
  const Mesh mesh = small_pipe();
  write_stl(dir.file("p.stl"), mesh, StlFormat::ascii);
  expect_same_mesh(mesh, read_stl(dir.file("p.stl")));
}

TEST(Stl, BinaryWhoseHeaderSaysSolidIsReadAsBinary) {
  TempDir dir;
  write_stl(dir.file("p.stl"), small_pipe(), StlFormat::binary);
  std::string bytes = test::read_text(dir.file("p.stl"));
  bytes.replace(0, 5, "solid");
  test::write_text(dir.file("q.stl"), bytes);
  EXPECT_EQ(read_stl(dir.file("q.stl")).faces.size(), small_pipe().faces.size());
}

TEST(Stl, MissingFileIsNamed) {
  const std::string msg = error_of("/nonexistent/pipe.stl");
  EXPECT_NE(msg.find("/nonexistent/pipe.stl"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
}

TEST(Stl, ADirectoryIsNamedAsOne) {
  TempDir dir;
  const std::string msg = error_of(dir.path());
  EXPECT_NE(msg.find("is a directory"), std::string::npos) << msg;
}

// Millimetres are the contract: the same pipe written in metres is refused with the likely cause.
TEST(Stl, AModelInMetresIsRefusedWithTheCause) {
  Mesh metres = small_pipe();
  for (auto& v : metres.vertices) v /= 1000.0f;
  try {
    derive_pipe_model(metres, "metres.stl");
    ADD_FAILURE() << "a 0.02 mm tube was accepted";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("in metres"), std::string::npos) << e.what();
  }
}

TEST(MakePipe, DiameterMustBeANumberAboveZero) {
  for (const double d : {0.0, -20.0, std::nan("")}) {
    PipeSpec spec;
    spec.diameter_mm = d;
    spec.segments = parse_centreline("S100");
    EXPECT_THROW(make_pipe(spec), ModelError) << d;
  }
}

TEST(Stl, EmptyFile) {
  TempDir dir;
  test::write_text(dir.file("e.stl"), "");
  EXPECT_NE(error_of(dir.file("e.stl")).find("empty"), std::string::npos);
}

TEST(Stl, TruncatedBinary) {
  TempDir dir;
  write_stl(dir.file("p.stl"), small_pipe(), StlFormat::binary);
  const std::string bytes = test::read_text(dir.file("p.stl"));
  test::write_text(dir.file("t.stl"), bytes.substr(0, bytes.size() - 30));
  const std::string msg = error_of(dir.file("t.stl"));
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
  EXPECT_NE(msg.find("t.stl"), std::string::npos) << msg;
}

TEST(Stl, TruncatedAscii) {
  TempDir dir;
  write_stl(dir.file("p.stl"), small_pipe(), StlFormat::ascii);
  const std::string text = test::read_text(dir.file("p.stl"));
  test::write_text(dir.file("t.stl"), text.substr(0, text.size() / 2));
  EXPECT_NE(error_of(dir.file("t.stl")).find("truncated"), std::string::npos) << error_of(dir.file("t.stl"));
}

// The loader's message for an ASCII STL of one facet whose first vertex is `first_vertex`.
std::string one_facet_error(const std::string& first_vertex) {
  TempDir dir;
  test::write_text(dir.file("f.stl"), "solid x\nfacet normal 0 0 1\nouter loop\nvertex " + first_vertex +
                                          "\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n");
  return error_of(dir.file("f.stl"));
}

TEST(Stl, AsciiWithBadVertex) {
  const std::string error = one_facet_error("0 0 zero");
  EXPECT_NE(error.find("vertex"), std::string::npos) << error;
}

// Found by tools/fuzz: coordinates of 1e30 mm overflowed the surface area to inf, and the
// model derivation then indexed out of its sample table.
TEST(Stl, CoordinatesBeyondAKilometreAreRefused) {
  const std::string error = one_facet_error("0 0 1e30");
  EXPECT_NE(error.find("beyond 1e6 mm"), std::string::npos) << error;
}

TEST(Stl, NotAnStl) {
  TempDir dir;
  test::write_text(dir.file("n.stl"), "hello, this is a text file and not a mesh");
  EXPECT_NE(error_of(dir.file("n.stl")).find("not an STL"), std::string::npos) << error_of(dir.file("n.stl"));
  test::write_text(dir.file("solid.stl"), "solid but nothing else\n");
  EXPECT_NE(error_of(dir.file("solid.stl")).find("no facets"), std::string::npos);
}

TEST(Stl, ZeroTriangleBinary) {
  TempDir dir;
  test::write_text(dir.file("z.stl"), std::string(84, '\0'));
  EXPECT_NE(error_of(dir.file("z.stl")).find("no triangles"), std::string::npos)
      << error_of(dir.file("z.stl"));
}

TEST(Centreline, ParsesAndRejects) {
  const auto segs = parse_centreline("S60,B90r50t30,S40");
  ASSERT_EQ(segs.size(), 3u);
  EXPECT_EQ(segs[1].kind, CentrelineSegment::bend);
  EXPECT_DOUBLE_EQ(segs[1].angle_deg, 90);
  EXPECT_DOUBLE_EQ(segs[1].radius_mm, 50);
  EXPECT_DOUBLE_EQ(segs[1].twist_deg, 30);
  EXPECT_THROW(parse_centreline("S60,X3"), ModelError);
  EXPECT_THROW(parse_centreline("B90"), ModelError);
  EXPECT_THROW(parse_centreline("S-5"), ModelError);
  EXPECT_THROW(parse_centreline(""), ModelError);
}

}  // namespace
}  // namespace pipeloc
