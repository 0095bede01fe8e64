#include "tools/report/mesh_decimate.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace kuavo::report {
namespace {

struct Box {
  std::array<float, 3> lo{}, hi{};
};

Box bounds(const Mesh& m) {
  Box b;
  if (m.vertices.empty()) return b;
  b.lo = b.hi = m.vertices[0];
  for (const auto& v : m.vertices) {
    for (int k = 0; k < 3; ++k) b.lo[k] = std::min(b.lo[k], v[k]), b.hi[k] = std::max(b.hi[k], v[k]);
  }
  return b;
}

bool read_ascii_stl(const std::string& text, Mesh& out) {
  std::istringstream in(text);
  std::string word;
  while (in >> word) {
    if (word != "vertex") continue;
    std::array<float, 3> v{};
    if (!(in >> v[0] >> v[1] >> v[2])) return false;
    out.vertices.push_back(v);
  }
  if (out.vertices.size() % 3 != 0) return false;
  for (std::uint32_t i = 0; i < out.vertices.size(); i += 3) out.triangles.push_back({i, i + 1, i + 2});
  return true;
}

template <class T>
void put(std::string& s, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // little-endian host (x86-64, the project's only target)
  s.append(b, sizeof(T));
}

}  // namespace

bool read_stl(const std::string& path, Mesh& out, std::string& error) {
  out = {};
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    error = path + ": cannot open";
    return false;
  }
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  // Binary STL: an 80-byte header, a count and 50 bytes per triangle; the size decides (some
  // binary files start with "solid" too).
  if (bytes.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if (bytes.size() == 84 + 50ull * n) {
      out.vertices.resize(3ull * n);
      out.triangles.resize(n);
      for (std::uint32_t t = 0; t < n; ++t) {
        const char* p = bytes.data() + 84 + 50ull * t + 12;  // skip the facet normal
        for (int k = 0; k < 3; ++k) std::memcpy(out.vertices[3ull * t + k].data(), p + 12 * k, 12);
        out.triangles[t] = {3 * t, 3 * t + 1, 3 * t + 2};
      }
      for (const auto& v : out.vertices) {
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
          error = path + ": non-finite vertex";
          return false;
        }
      }
      return true;
    }
  }
  if (bytes.rfind("solid", 0) == 0 && read_ascii_stl(bytes, out)) return true;
  error = path + ": neither binary nor ASCII STL";
  return false;
}

Mesh cluster_vertices(const Mesh& in, double cell_m) {
  Mesh out;
  const Box box = bounds(in);
  std::map<std::array<std::int64_t, 3>, std::uint32_t> cell_index;  // ordered: deterministic output
  std::vector<std::array<double, 4>> sums;                          // x, y, z, count per cluster
  std::vector<std::uint32_t> cluster_of(in.vertices.size());
  for (std::size_t i = 0; i < in.vertices.size(); ++i) {
    std::array<std::int64_t, 3> key{};
    for (int k = 0; k < 3; ++k) {
      key[k] = cell_m > 0.0 ? static_cast<std::int64_t>(std::floor((in.vertices[i][k] - box.lo[k]) / cell_m)) : 0;
    }
    if (cell_m <= 0.0) {  // weld identical positions only
      std::int32_t bits[3];
      std::memcpy(bits, in.vertices[i].data(), 12);
      key = {bits[0], bits[1], bits[2]};
    }
    auto [it, inserted] = cell_index.emplace(key, static_cast<std::uint32_t>(sums.size()));
    if (inserted) sums.push_back({0.0, 0.0, 0.0, 0.0});
    auto& s = sums[it->second];
    for (int k = 0; k < 3; ++k) s[k] += in.vertices[i][k];
    s[3] += 1.0;
    cluster_of[i] = it->second;
  }
  out.vertices.reserve(sums.size());
  for (const auto& s : sums) {
    out.vertices.push_back({static_cast<float>(s[0] / s[3]), static_cast<float>(s[1] / s[3]), static_cast<float>(s[2] / s[3])});
  }
  std::set<std::array<std::uint32_t, 3>> seen;
  for (const auto& t : in.triangles) {
    const std::array<std::uint32_t, 3> c{cluster_of[t[0]], cluster_of[t[1]], cluster_of[t[2]]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    // The same triangle with either winding is kept once (both faces of a thin wall collapse
    // onto one; the browser draws both sides).
    std::array<std::uint32_t, 3> key = c;
    std::sort(key.begin(), key.end());
    if (!seen.insert(key).second) continue;
    out.triangles.push_back(c);
  }
  // Drop the vertices no triangle uses (clusters of collapsed triangles only).
  std::vector<std::int64_t> remap(out.vertices.size(), -1);
  Mesh packed;
  for (auto& t : out.triangles) {
    for (auto& v : t) {
      if (remap[v] < 0) {
        remap[v] = static_cast<std::int64_t>(packed.vertices.size());
        packed.vertices.push_back(out.vertices[v]);
      }
      v = static_cast<std::uint32_t>(remap[v]);
    }
  }
  packed.triangles = std::move(out.triangles);
  return packed;
}

DecimateResult decimate(const Mesh& in, std::size_t max_triangles) {
  DecimateResult r;
  r.mesh = cluster_vertices(in, 0.0);
  if (r.mesh.triangles.size() <= max_triangles) return r;
  const Box box = bounds(in);
  double diagonal = 0.0;
  for (int k = 0; k < 3; ++k) diagonal += double(box.hi[k] - box.lo[k]) * (box.hi[k] - box.lo[k]);
  double lo = 0.0, hi = std::sqrt(diagonal);
  Mesh best = cluster_vertices(in, hi);
  for (int step = 0; step < 24; ++step) {
    const double mid = 0.5 * (lo + hi);
    Mesh m = cluster_vertices(in, mid);
    if (m.triangles.size() <= max_triangles) {
      hi = mid;
      best = std::move(m);
    } else {
      lo = mid;
    }
  }
  r.mesh = std::move(best);
  r.cell_m = hi;
  return r;
}

std::string encode_mesh(const Mesh& m) {
  std::string s;
  const Box box = bounds(m);
  float extent = 0.0f;
  for (int k = 0; k < 3; ++k) extent = std::max(extent, box.hi[k] - box.lo[k]);
  const float step = extent > 0.0f ? extent / 65000.0f : 1.0f;
  // Centre the range on the box so int16 covers it: i = round((x - centre) / step) in ±32 500.
  std::array<float, 3> centre{};
  for (int k = 0; k < 3; ++k) centre[k] = 0.5f * (box.lo[k] + box.hi[k]);
  put<std::uint32_t>(s, static_cast<std::uint32_t>(m.vertices.size()));
  put<std::uint32_t>(s, static_cast<std::uint32_t>(m.triangles.size()));
  for (float c : centre) put<float>(s, c);
  put<float>(s, step);
  for (const auto& v : m.vertices) {
    for (int k = 0; k < 3; ++k) put<std::int16_t>(s, static_cast<std::int16_t>(std::lround((v[k] - centre[k]) / step)));
  }
  while (s.size() % 4 != 0) s.push_back('\0');
  const bool wide = m.vertices.size() > 65535;
  for (const auto& t : m.triangles) {
    for (auto v : t) wide ? put<std::uint32_t>(s, v) : put<std::uint16_t>(s, static_cast<std::uint16_t>(v));
  }
  while (s.size() % 4 != 0) s.push_back('\0');
  return s;
}

}  // namespace kuavo::report
