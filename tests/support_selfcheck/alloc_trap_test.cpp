// The allocation trap must see what it claims to see, or every zero-allocation
// test built on it proves nothing.
#include "tests/support/alloc_trap.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <memory>
#include <vector>

namespace kuavo::test {
namespace {

// Keeps the compiler from eliding an allocation whose result is unused.
template <typename T>
void escape(T* p) {
  asm volatile("" : : "g"(p) : "memory");
}

TEST(AllocTrap, CountsOperatorNew) {
  AllocTrap trap;
  auto p = std::make_unique<int>(3);
  escape(p.get());
  EXPECT_GE(trap.count(), 1u);
  EXPECT_EQ(*p, 3);
}

TEST(AllocTrap, CountsVectorGrowthAndMalloc) {
  AllocTrap trap;
  std::vector<double> v;
  v.resize(100);
  escape(v.data());
  void* raw = std::malloc(64);
  escape(raw);
  std::free(raw);
  EXPECT_GE(trap.count(), 2u);
}

TEST(AllocTrap, FixedSizeEigenDoesNotAllocate) {
  Eigen::Matrix<double, 12, 12> a = Eigen::Matrix<double, 12, 12>::Identity();
  Eigen::Matrix<double, 12, 1> b = Eigen::Matrix<double, 12, 1>::Ones();
  AllocTrap trap;
  Eigen::Matrix<double, 12, 1> c = a.llt().solve(b);
  EXPECT_EQ(trap.count(), 0u);
  EXPECT_DOUBLE_EQ(c(3), 1.0);
}

TEST(AllocTrap, DynamicEigenInsideTrapIsCaughtByEigen) {
  // EIGEN_RUNTIME_NO_MALLOC turns a dynamic Eigen allocation into an assertion
  // in debug builds; in release builds the malloc counter still sees it.
  AllocTrap trap;
  Eigen::internal::set_is_malloc_allowed(true);  // let it through, then count it
  Eigen::VectorXd v(50);
  v.setZero();
  escape(v.data());
  EXPECT_GE(trap.count(), 1u);
}

TEST(AllocTrap, NestedScopesCountFromTheirOwnStart) {
  AllocTrap outer;
  auto a = std::make_unique<int>(1);
  escape(a.get());
  const std::size_t before = outer.count();
  {
    AllocTrap inner;
    EXPECT_EQ(inner.count(), 0u);
  }
  EXPECT_EQ(outer.count(), before);
}

}  // namespace
}  // namespace kuavo::test
