// qp_tests_avx512 (tests/qp/CMakeLists.txt) is compiled for x86-64-v4 but built and run by CI
// on machines that may lack AVX-512: there every test skips before its own code runs, instead
// of dying on the first AVX-512 instruction.
#include <gtest/gtest.h>

namespace {

class RequireAvx512 : public ::testing::Environment {
 public:
  void SetUp() override {
    if (!__builtin_cpu_supports("avx512f")) GTEST_SKIP() << "this CPU has no AVX-512 (avx512f)";
  }
};

[[maybe_unused]] const ::testing::Environment* const kRequireAvx512 =
    ::testing::AddGlobalTestEnvironment(new RequireAvx512);

}  // namespace
