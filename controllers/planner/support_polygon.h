// Support polygon and centre-of-pressure margin, for the closed loop's balance figure
// (zmp_margin_m_min). On flat ground the ZMP is the centre of pressure of the contact
// forces; its margin is the signed distance to the edge of the convex hull of the soles
// in contact (positive inside). Header-only, no allocation.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Core>

namespace kuavo::planner {

template <int N>
struct Polygon2 {
  std::array<Eigen::Vector2d, N> vertex{};  // counter-clockwise
  int count = 0;
};

// Convex hull (Andrew's monotone chain), counter-clockwise, collinear points dropped.
template <int N>
Polygon2<N> convex_hull(std::array<Eigen::Vector2d, N> points, int n) {
  // Insertion sort by (x, y): n ≤ N is tiny (std::sort also trips GCC 12's -Warray-bounds here).
  for (int i = 1; i < n; ++i) {
    const Eigen::Vector2d key = points[i];
    int j = i - 1;
    while (j >= 0 && (points[j].x() > key.x() || (points[j].x() == key.x() && points[j].y() > key.y()))) {
      points[j + 1] = points[j];
      --j;
    }
    points[j + 1] = key;
  }
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::array<Eigen::Vector2d, 2 * N> h{};
  int k = 0;
  for (int i = 0; i < n; ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], points[i]) <= 0.0) --k;
    h[k++] = points[i];
  }
  for (int i = n - 2, lower = k + 1; i >= 0; --i) {
    while (k >= lower && cross(h[k - 2], h[k - 1], points[i]) <= 0.0) --k;
    h[k++] = points[i];
  }
  Polygon2<N> out;
  out.count = std::max(0, std::min(k - 1, N));
  for (int i = 0; i < out.count; ++i) out.vertex[i] = h[i];
  return out;
}

// Signed distance from p to the boundary of a convex counter-clockwise polygon:
// positive inside. Fewer than 3 vertices: the negative distance to the segment/point.
template <int N>
double signed_margin(const Polygon2<N>& poly, const Eigen::Vector2d& p) {
  if (poly.count == 0) return -1e9;
  if (poly.count < 3) {
    const Eigen::Vector2d a = poly.vertex[0], b = poly.vertex[poly.count - 1];
    const Eigen::Vector2d d = b - a;
    const double s = d.squaredNorm() > 0.0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
    return -(a + s * d - p).norm();
  }
  double inside = 1e9, outside = 0.0;
  bool is_inside = true;
  for (int i = 0; i < poly.count; ++i) {
    const Eigen::Vector2d a = poly.vertex[i], b = poly.vertex[(i + 1) % poly.count];
    const Eigen::Vector2d d = b - a;
    const double dist = (d.x() * (p.y() - a.y()) - d.y() * (p.x() - a.x())) / d.norm();  // left of edge > 0
    inside = std::min(inside, dist);
    if (dist < 0.0) is_inside = false;
    const double s = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    const double to_edge = (a + s * d - p).norm();
    outside = i == 0 ? to_edge : std::min(outside, to_edge);
  }
  return is_inside ? inside : -outside;
}

}  // namespace kuavo::planner

namespace kuavo::planner {

// The point of the polygon nearest to p, then pulled margin_m towards the vertex
// centroid (a cheap inward offset; exact for margins small against the polygon).
template <int N>
Eigen::Vector2d project_into(const Polygon2<N>& poly, const Eigen::Vector2d& p, double margin_m) {
  if (poly.count == 0) return p;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (int i = 0; i < poly.count; ++i) centroid += poly.vertex[i];
  centroid /= poly.count;
  Eigen::Vector2d nearest = p;
  if (signed_margin(poly, p) < margin_m) {
    double best = 1e18;
    for (int i = 0; i < poly.count; ++i) {
      const Eigen::Vector2d a = poly.vertex[i], b = poly.vertex[(i + 1) % poly.count];
      const Eigen::Vector2d d = b - a;
      const double s = d.squaredNorm() > 0.0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      const Eigen::Vector2d c = a + s * d;
      if ((c - p).squaredNorm() < best) best = (c - p).squaredNorm(), nearest = c;
    }
    const Eigen::Vector2d in = centroid - nearest;
    const double len = in.norm();
    nearest += len > margin_m ? (margin_m / len) * in : in;
  }
  return nearest;
}

}  // namespace kuavo::planner
