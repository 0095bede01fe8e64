#include "controllers/estimator/linear_kf.h"

namespace kuavo::estimator {

namespace {

constexpr int kPoints = model::kNumContactPoints;

// One axis's sub-filter: its 11 states, its 11×11 block of P (see linear_kf.h), padded
// to 12 with a row and column so that each column is three whole AVX packets. The padding
// never enters the real entries (each entry of a rank-one update is computed on its own);
// it is zeroed so that it holds no garbage.
constexpr int kAxisPadded = kAxisStates + 1;
using AxisVector = Eigen::Matrix<double, kAxisPadded, 1>;
using AxisCovariance = Eigen::Matrix<double, kAxisPadded, kAxisPadded>;

// Local indices within an axis (state index = 3·local + k).
constexpr int kLocalPosition = 0;
constexpr int kLocalVelocity = 1;
constexpr int local_point(int i) { return 2 + i; }

// A row of C restricted to one axis: (a, ca) [+ (b, cb)]; b < 0 when absent.
struct SparseRow {
  int a;
  double ca;
  int b;
  double cb;
};

// One scalar update of an axis's sub-filter (the same arithmetic, element for element, as
// the update of the full 33-state filter: the other axes' entries of P cᵀ are exact zeros).
void scalar_update(AxisVector& x, AxisCovariance& p, const SparseRow& r, double y, double variance, AxisVector& pc) {
  pc = r.ca * p.col(r.a);
  double cx = r.ca * x[r.a];
  if (r.b >= 0) {
    pc += r.cb * p.col(r.b);
    cx += r.cb * x[r.b];
  }
  const double s = r.ca * pc[r.a] + (r.b >= 0 ? r.cb * pc[r.b] : 0.0) + variance;
  const double gain_scale = 1.0 / s;
  x += (gain_scale * (y - cx)) * pc;
  p.noalias() -= (gain_scale * pc) * pc.transpose();
}

}  // namespace

bool kf_axes_separated(const KfCovariance& p) {
  for (int j = 0; j < kStateDim; ++j) {
    for (int i = 0; i < kStateDim; ++i) {
      if (i % 3 != j % 3 && p(i, j) != 0.0) return false;
    }
  }
  return true;
}

void kf_predict_rt(KfVector& x, KfCovariance& p, const Eigen::Vector3d& a_world_m_s2,
                   const KfVector& process_variance, double dt_s) {
  const Eigen::Vector3d a = a_world_m_s2 - x.segment<3>(kBiasIndex);
  const double h = 0.5 * dt_s * dt_s;
  x.head<3>() += dt_s * x.segment<3>(3) + h * a;
  x.segment<3>(3) += dt_s * a;
  // A P, rows: position rows first (they read the old velocity rows), then velocity rows.
  p.topRows<3>() += dt_s * p.middleRows<3>(3) - h * p.middleRows<3>(kBiasIndex);
  p.middleRows<3>(3) -= dt_s * p.middleRows<3>(kBiasIndex);
  // (A P) Aᵀ, columns: the same.
  p.leftCols<3>() += dt_s * p.middleCols<3>(3) - h * p.middleCols<3>(kBiasIndex);
  p.middleCols<3>(3) -= dt_s * p.middleCols<3>(kBiasIndex);
  p.diagonal() += process_variance;
}

void kf_update_rt(KfVector& x, KfCovariance& p, const KfMeasurementVector& y,
                  const KfMeasurementVector& measurement_variance, KfMeasurementVector& innovation) {
  innovation = y - kf_predicted_measurement(x);
  // Axis by axis: the cross-axis blocks of P are zero and stay zero (linear_kf.h), so each
  // axis is an 11-state filter of its own. Within an axis the rows keep the order of the
  // 33-state sequential update (positions, fused velocity, heights); updates of different
  // axes touch disjoint entries, so their interleaving does not matter.
  AxisVector xk = AxisVector::Zero(), pc;
  AxisCovariance pk = AxisCovariance::Zero();
  for (int k = 0; k < 3; ++k) {
    for (int a = 0; a < kAxisStates; ++a) {
      xk[a] = x[3 * a + k];
      for (int b = 0; b < kAxisStates; ++b) pk(b, a) = p(3 * b + k, 3 * a + k);
    }
    for (int i = 0; i < kPoints; ++i) {
      const int m = kPositionRows + 3 * i + k;
      scalar_update(xk, pk, {local_point(i), 1.0, kLocalPosition, -1.0}, y[m], measurement_variance[m], pc);
    }
    // The 8 velocity rows of one axis share their row of C (−v_k): in information
    // form they are exactly one row with the inverse-variance-weighted mean and
    // variance 1/Σ(1/r). 24 updates become 3.
    double information = 0.0, weighted_sum = 0.0;
    for (int i = 0; i < kPoints; ++i) {
      const int m = kVelocityRows + 3 * i + k;
      information += 1.0 / measurement_variance[m];
      weighted_sum += y[m] / measurement_variance[m];
    }
    scalar_update(xk, pk, {kLocalVelocity, -1.0, -1, 0.0}, weighted_sum / information, 1.0 / information, pc);
    if (k == 2) {
      for (int i = 0; i < kPoints; ++i) {
        const int m = kHeightRows + i;
        scalar_update(xk, pk, {local_point(i), 1.0, -1, 0.0}, y[m], measurement_variance[m], pc);
      }
    }
    // Back into P, symmetrised on the way: rounding in the rank-one downdates leaves the
    // block slightly asymmetric; Leju symmetrises too.
    for (int a = 0; a < kAxisStates; ++a) {
      x[3 * a + k] = xk[a];
      p(3 * a + k, 3 * a + k) = pk(a, a);
      for (int b = a + 1; b < kAxisStates; ++b) {
        const double mean = 0.5 * (pk(b, a) + pk(a, b));
        p(3 * b + k, 3 * a + k) = mean;
        p(3 * a + k, 3 * b + k) = mean;
      }
    }
  }
}

bool kf_bound_horizontal_rt(KfCovariance& p, double det_limit_m4) {
  const double det_m4 = p(0, 0) * p(1, 1) - p(0, 1) * p(1, 0);
  if (!(det_m4 > det_limit_m4)) return false;
  p.topRightCorner<2, kStateDim - 2>().setZero();
  p.bottomLeftCorner<kStateDim - 2, 2>().setZero();
  p.topLeftCorner<2, 2>() /= 10.0;
  return true;
}

KfMeasurementVector kf_predicted_measurement(const KfVector& x) {
  KfMeasurementVector y;
  for (int i = 0; i < kPoints; ++i) {
    y.segment<3>(kPositionRows + 3 * i) = x.segment<3>(point_index(i, 0)) - x.head<3>();
    y.segment<3>(kVelocityRows + 3 * i) = -x.segment<3>(3);
    y[kHeightRows + i] = x[point_index(i, 2)];
  }
  return y;
}

}  // namespace kuavo::estimator
