// Allocation trap: counts every malloc/calloc/realloc/operator new made by the
// current thread while an AllocTrap is alive, and switches Eigen's runtime
// malloc check off for the same scope. Linking this file into a binary
// replaces the global allocation functions (glibc's __libc_* underneath).
//
//   {
//     kuavo::test::AllocTrap trap;
//     control_step(...);
//     EXPECT_EQ(trap.count(), 0);
//   }
#pragma once

#include <cstddef>

namespace kuavo::test {

class AllocTrap {
 public:
  AllocTrap();
  ~AllocTrap();
  AllocTrap(const AllocTrap&) = delete;
  AllocTrap& operator=(const AllocTrap&) = delete;

  // Allocations made by this thread since the trap was armed.
  [[nodiscard]] std::size_t count() const;
  // Size in bytes of the first trapped allocation (0 if none), to help debugging.
  [[nodiscard]] std::size_t first_size_bytes() const;

 private:
  std::size_t start_count_;
  bool eigen_was_allowed_;
};

// Allocations by this thread since the process started (armed or not).
std::size_t thread_allocation_count();

}  // namespace kuavo::test
