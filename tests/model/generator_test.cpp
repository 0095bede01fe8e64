// The committed model tables are exactly what the generator makes from
// shared/robot today, and the generator refuses broken inputs with clear errors.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "tools/urdf2model/urdf_model.h"

namespace kuavo::test {
namespace {

namespace fs = std::filesystem;

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string kRobotDir = std::string(KUAVO_SHARED_DIR) + "/robot";

TEST(ModelGenerator, CommittedTablesMatchRegeneration) {
  for (const char* v : {"s45", "s42"}) {
    const auto result = tools::generate_model_tables(tools::default_generator_input(kRobotDir, v));
    ASSERT_TRUE(result.ok) << result.error;
    const fs::path committed =
        fs::path(KUAVO_SOURCE_DIR) / "controllers/model/generated" / (std::string("biped_") + v + "_tables.h");
    const std::string on_disk = read_file(committed);
    // Report the first differing line, not two 20 KB strings.
    std::istringstream a(result.source), b(on_disk);
    std::string la, lb;
    int line = 0;
    while (true) {
      const bool more_a = static_cast<bool>(std::getline(a, la));
      const bool more_b = static_cast<bool>(std::getline(b, lb));
      ++line;
      if (!more_a && !more_b) break;
      ASSERT_EQ(la, lb) << committed << ":" << line
                        << " is stale: run build/urdf2model from the source root and commit the result";
    }
  }
}

class BrokenUrdf : public ::testing::Test {
 protected:
  void SetUp() override {
    input_ = tools::default_generator_input(kRobotDir, "s45");
    original_ = read_file(input_.urdf_path);
    ASSERT_FALSE(original_.empty());
    dir_ = fs::temp_directory_path() / ("kuavo_urdf_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string generate_with(const std::string& urdf_text) {
    const fs::path p = dir_ / "robot.urdf";
    std::ofstream(p) << urdf_text;
    auto in = input_;
    in.urdf_path = p.string();
    const auto result = tools::generate_model_tables(in);
    EXPECT_FALSE(result.ok);
    return result.error;
  }

  tools::GeneratorInput input_;
  std::string original_;
  fs::path dir_;
};

TEST_F(BrokenUrdf, MissingJointIsNamed) {
  // Turn the knee joint into an unknown name.
  std::string text = std::regex_replace(original_, std::regex("\"leg_l4_joint\""), "\"leg_l4_renamed\"");
  const std::string err = generate_with(text);
  EXPECT_NE(err.find("leg_l4_joint"), std::string::npos) << err;
  EXPECT_NE(err.find("not found"), std::string::npos) << err;
}

TEST_F(BrokenUrdf, NonPositiveDefiniteInertiaIsRejected) {
  const std::string needle = "ixx=\"0.93103133\"";
  ASSERT_NE(original_.find(needle), std::string::npos);
  std::string text = original_;
  text.replace(text.find(needle), needle.size(), "ixx=\"-0.5\"");
  const std::string err = generate_with(text);
  EXPECT_NE(err.find("base_link"), std::string::npos) << err;
  EXPECT_NE(err.find("positive definite"), std::string::npos) << err;
}

TEST_F(BrokenUrdf, TriangleInequalityViolationIsRejected) {
  std::string text = original_;
  const std::string needle = "izz=\"0.27686612\"";
  ASSERT_NE(text.find(needle), std::string::npos);
  text.replace(text.find(needle), needle.size(), "izz=\"5.0\"");
  const std::string err = generate_with(text);
  EXPECT_NE(err.find("triangle inequality"), std::string::npos) << err;
}

TEST_F(BrokenUrdf, WrongJointCountIsRejected) {
  // An extra revolute joint (a 29th) hanging off the head.
  const std::string extra =
      "<link name=\"extra_link\"><inertial><origin xyz=\"0 0 0\" rpy=\"0 0 0\"/><mass value=\"0.1\"/>"
      "<inertia ixx=\"1e-4\" ixy=\"0\" ixz=\"0\" iyy=\"1e-4\" iyz=\"0\" izz=\"1e-4\"/></inertial></link>"
      "<joint name=\"extra_joint\" type=\"revolute\"><origin xyz=\"0 0 0.1\" rpy=\"0 0 0\"/>"
      "<parent link=\"zhead_2_link\"/><child link=\"extra_link\"/><axis xyz=\"0 0 1\"/>"
      "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>";
  std::string text = original_;
  text.replace(text.rfind("</robot>"), 8, extra);
  const std::string err = generate_with(text);
  EXPECT_NE(err.find("29 revolute joints"), std::string::npos) << err;
  EXPECT_NE(err.find("28"), std::string::npos) << err;
}

TEST_F(BrokenUrdf, MalformedXmlAndMissingFileAreReported) {
  EXPECT_NE(generate_with(original_.substr(0, original_.size() / 2)).find("cannot read URDF"), std::string::npos);
  auto in = input_;
  in.urdf_path = (dir_ / "absent.urdf").string();
  const auto result = tools::generate_model_tables(in);
  EXPECT_FALSE(result.ok);
  EXPECT_NE(result.error.find("absent.urdf"), std::string::npos) << result.error;
}

TEST(ModelGenerator, UnknownVariantIsRejected) {
  auto in = tools::default_generator_input(kRobotDir, "s45");
  in.variant = "s44";
  const auto result = tools::generate_model_tables(in);
  EXPECT_FALSE(result.ok);
  EXPECT_NE(result.error.find("s44"), std::string::npos);
}

}  // namespace
}  // namespace kuavo::test
