// Mesh decimation for the report's 3D view, against closed forms: a sphere's triangles, its
// radius after clustering, the encoded layout read back by hand, and STL files written here.
#include "tools/report/mesh_decimate.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace kuavo::report {
namespace {

// A UV sphere of radius r as a triangle soup (every triangle with its own 3 vertices, as STL).
Mesh soup_sphere(double r, int rings, int segments) {
  Mesh m;
  auto at = [&](int i, int j) {
    // Seam and poles exact, so equal points are equal bits (as in an STL export).
    if (i == 0 || i == rings) return std::array<float, 3>{0.0f, 0.0f, float(i == 0 ? r : -r)};
    j %= segments;
    const double th = M_PI * i / rings, ph = 2 * M_PI * j / segments;
    return std::array<float, 3>{float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)),
                                float(r * std::cos(th))};
  };
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const auto a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      for (const auto& tri : {std::array{a, b, c}, std::array{a, c, d}}) {
        const auto n = static_cast<std::uint32_t>(m.vertices.size());
        m.vertices.insert(m.vertices.end(), tri.begin(), tri.end());
        m.triangles.push_back({n, n + 1, n + 2});
      }
    }
  }
  return m;
}

TEST(MeshDecimate, MeetsTheBudgetAndKeepsTheShapeWithinACell) {
  const Mesh sphere = soup_sphere(0.1, 60, 120);  // 14 400 triangles, poles degenerate
  const DecimateResult d = decimate(sphere, 800);
  EXPECT_LE(d.mesh.triangles.size(), 800u);
  EXPECT_GE(d.mesh.triangles.size(), 200u);  // the smallest cell that fits: not a handful of faces
  ASSERT_GT(d.cell_m, 0.0);
  // Every vertex is the mean of sphere points within one cell: its radius is off by at most
  // a cell diagonal (inward, since the mean of points on a sphere lies inside it).
  for (const auto& v : d.mesh.vertices) {
    const double r = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    EXPECT_LE(r, 0.1 + 1e-6);
    EXPECT_GE(r, 0.1 - std::sqrt(3.0) * d.cell_m);
  }
  for (const auto& t : d.mesh.triangles) {
    EXPECT_NE(t[0], t[1]);
    EXPECT_NE(t[1], t[2]);
    EXPECT_NE(t[0], t[2]);
    for (auto i : t) EXPECT_LT(i, d.mesh.vertices.size());
  }
}

TEST(MeshDecimate, WeldsASoupWithoutLosingATriangleWhenWithinBudget) {
  const Mesh sphere = soup_sphere(0.1, 6, 8);  // 96 triangles, 8 degenerate at each pole
  const DecimateResult d = decimate(sphere, 1000);
  EXPECT_EQ(d.cell_m, 0.0);
  EXPECT_EQ(d.mesh.triangles.size(), 96u - 2 * 8);
  EXPECT_EQ(d.mesh.vertices.size(), 5u * 8 + 2);  // 5 inner rings of 8, two poles
}

TEST(MeshDecimate, EncodingReadsBackWithinItsStep) {
  const Mesh m = decimate(soup_sphere(0.2, 20, 40), 300).mesh;
  const std::string bytes = encode_mesh(m);
  std::uint32_t nv = 0, nt = 0;
  float centre[3], step = 0.0f;
  std::memcpy(&nv, bytes.data(), 4);
  std::memcpy(&nt, bytes.data() + 4, 4);
  std::memcpy(centre, bytes.data() + 8, 12);
  std::memcpy(&step, bytes.data() + 20, 4);
  ASSERT_EQ(nv, m.vertices.size());
  ASSERT_EQ(nt, m.triangles.size());
  EXPECT_NEAR(step, 0.4f / 65000.0f, 1e-7);
  for (std::uint32_t i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) {
      std::int16_t q = 0;
      std::memcpy(&q, bytes.data() + 24 + 6 * i + 2 * k, 2);
      EXPECT_NEAR(centre[k] + step * q, m.vertices[i][k], step);
    }
  }
  const std::size_t at = (24 + 6 * nv + 3) & ~std::size_t{3};
  ASSERT_EQ(bytes.size(), (at + 6 * nt + 3) & ~std::size_t{3});
  for (std::uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      std::uint16_t v = 0;
      std::memcpy(&v, bytes.data() + at + 6 * t + 2 * k, 2);
      EXPECT_EQ(v, m.triangles[t][k]);
    }
  }
}

TEST(MeshDecimate, ReadsBinaryAndAsciiStlAndRefusesOthers) {
  const auto dir = std::filesystem::temp_directory_path() / ("kuavo_stl_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const float tri[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}};
  {
    std::ofstream bin(dir / "one.stl", std::ios::binary);
    char header[80] = "solid but binary";  // binary files may start with "solid" too
    bin.write(header, 80);
    const std::uint32_t n = 1;
    bin.write(reinterpret_cast<const char*>(&n), 4);
    const float normal[3] = {0, 0, 1};
    bin.write(reinterpret_cast<const char*>(normal), 12);
    bin.write(reinterpret_cast<const char*>(tri), 36);
    const std::uint16_t attr = 0;
    bin.write(reinterpret_cast<const char*>(&attr), 2);
  }
  std::ofstream(dir / "one_ascii.stl") << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                          "vertex 0 2 0\nendloop\nendfacet\nendsolid t\n";
  std::ofstream(dir / "junk.stl") << "not a mesh";
  for (const char* name : {"one.stl", "one_ascii.stl"}) {
    Mesh m;
    std::string error;
    ASSERT_TRUE(read_stl((dir / name).string(), m, error)) << error;
    ASSERT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(m.vertices[2][1], 2.0f) << name;
  }
  Mesh m;
  std::string error;
  EXPECT_FALSE(read_stl((dir / "junk.stl").string(), m, error));
  EXPECT_NE(error.find("junk.stl"), std::string::npos);
  EXPECT_FALSE(read_stl((dir / "missing.stl").string(), m, error));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace kuavo::report
