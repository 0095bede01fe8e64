// Triangle meshes for the HTML report's 3D replay: Leju's STL files (binary or ASCII) read and
// reduced for the browser by vertex clustering (Rossignac-Borrel): vertices are snapped to a
// uniform grid, each occupied cell becomes one vertex (the mean of its members) and triangles
// that collapse are dropped. The cell is the smallest one (found by bisection) that meets a
// triangle budget, so every surface point moves by at most one cell diagonal. Clustering keeps
// the silhouette, needs no connectivity (Leju's STL files are triangle soups) and is a few
// dozen lines; quadric edge collapse would keep flat regions better but is not needed at the
// ~1 000 triangles per link a replay shows (Debian's meshlab has it, but as a GUI application
// with a large dependency tree and version-specific filter scripts: too much for a build step
// of a report). Runs at report time from ../shared, so no derived mesh is committed.
// Offline code; allocates.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace kuavo::report {

struct Mesh {
  std::vector<std::array<float, 3>> vertices;       // metres, the file's frame
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// Reads binary or ASCII STL. false with "PATH: why" in error.
bool read_stl(const std::string& path, Mesh& out, std::string& error);

// Clusters on a grid of cell_m; drops degenerate and repeated triangles.
Mesh cluster_vertices(const Mesh& in, double cell_m);

struct DecimateResult {
  Mesh mesh;
  double cell_m = 0.0;  // 0 when the input met the budget as it was (then mesh == welded input)
};
// The smallest cell (bisection, 24 steps between 0 and the bounding box's diagonal) whose
// clustering has at most max_triangles.
DecimateResult decimate(const Mesh& in, std::size_t max_triangles);

// Compact little-endian encoding for the browser: uint32 vertex count, uint32 triangle count,
// float32 centre[3], float32 step_m, then int16 x, y, z per vertex (position = centre + step·i),
// padded to 4 bytes, then uint16 indices (uint32 if more than 65 535 vertices) per triangle.
// The step is the bounding box's largest side / 65 000: under 0.01 mm for a link.
std::string encode_mesh(const Mesh& m);

}  // namespace kuavo::report
