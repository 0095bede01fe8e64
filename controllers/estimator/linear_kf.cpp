#include "controllers/estimator/linear_kf.h"

namespace kuavo::estimator {

namespace {

constexpr int kPoints = model::kNumContactPoints;

// Row m of C as up to two (index, coefficient) pairs; b < 0 when absent.
struct SparseRow {
  int a;
  double ca;
  int b;
  double cb;
};

SparseRow row_of(int m) {
  if (m < kVelocityRows) {
    const int i = m / 3, k = m % 3;
    return {point_index(i, k), 1.0, k, -1.0};
  }
  if (m < kHeightRows) return {3 + (m - kVelocityRows) % 3, -1.0, -1, 0.0};
  return {point_index(m - kHeightRows, 2), 1.0, -1, 0.0};
}

}  // namespace

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

// One scalar update with the sparse row (a, ca) [+ (b, cb)] of C.
void scalar_update(KfVector& x, KfCovariance& p, const SparseRow& r, double y, double variance, KfVector& pc) {
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

void kf_update_rt(KfVector& x, KfCovariance& p, const KfMeasurementVector& y,
                  const KfMeasurementVector& measurement_variance, KfMeasurementVector& innovation) {
  innovation = y - kf_predicted_measurement(x);
  KfVector pc;  // P cᵀ for the current row
  for (int m = 0; m < kVelocityRows; ++m) scalar_update(x, p, row_of(m), y[m], measurement_variance[m], pc);
  // The 8 velocity rows of one axis share their row of C (−v_k): in information
  // form they are exactly one row with the inverse-variance-weighted mean and
  // variance 1/Σ(1/r). 24 updates become 3.
  for (int k = 0; k < 3; ++k) {
    double information = 0.0, weighted_sum = 0.0;
    for (int i = 0; i < kPoints; ++i) {
      const int m = kVelocityRows + 3 * i + k;
      information += 1.0 / measurement_variance[m];
      weighted_sum += y[m] / measurement_variance[m];
    }
    scalar_update(x, p, row_of(kVelocityRows + k), weighted_sum / information, 1.0 / information, pc);
  }
  for (int m = kHeightRows; m < kMeasurementDim; ++m) scalar_update(x, p, row_of(m), y[m], measurement_variance[m], pc);
  // Rounding in the rank-one downdates leaves P slightly asymmetric; Leju symmetrises too.
  // In place, pairwise: no 7 KB temporary on the real-time stack.
  for (int j = 0; j < kStateDim; ++j) {
    for (int i = j + 1; i < kStateDim; ++i) {
      const double mean = 0.5 * (p(i, j) + p(j, i));
      p(i, j) = mean;
      p(j, i) = mean;
    }
  }
}

bool kf_axes_separated(const KfCovariance& p) {
  for (int j = 0; j < kStateDim; ++j) {
    for (int i = 0; i < kStateDim; ++i) {
      if (i % 3 != j % 3 && p(i, j) != 0.0) return false;
    }
  }
  return true;
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
