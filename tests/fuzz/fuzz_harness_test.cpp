// The fuzz harness's own judge: it must catch every way a program can fail (a crash, a hang,
// an exit code outside {0, 1, 2}, non-finite or null output), and its mutations must be
// reproducible from the seed and start from inputs the programs accept.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "tests/fuzz/fuzz_inputs.h"
#include "tests/fuzz/run_limited.h"

namespace kuavo::fuzz {
namespace {

RunResult sh(const std::string& script, const RunLimits& limits = {}) {
  const std::string dir = testing::TempDir();
  return run_limited({"/bin/sh", "-c", script}, dir, limits);
}

TEST(FuzzJudge, EveryAbnormalEndIsAFinding) {
  RunLimits limits;
  limits.timeout_s = 0.3;
  EXPECT_EQ(judge_end(sh("echo fine; exit 0", limits), limits), "");
  EXPECT_EQ(judge_end(sh("exit 1", limits), limits), "");
  EXPECT_EQ(judge_end(sh("exit 2", limits), limits), "");
  EXPECT_EQ(judge_end(sh("exit 3", limits), limits), "exit 3");
  EXPECT_EQ(judge_end(sh("exit 134", limits), limits), "exit 134");
  EXPECT_NE(judge_end(sh("kill -SEGV $$", limits), limits).find("crash: signal 11"), std::string::npos);
  EXPECT_NE(judge_end(sh("kill -ABRT $$", limits), limits).find("crash: signal 6"), std::string::npos);
  // A run that does not end within the limit is killed and called a hang (no time is asserted).
  EXPECT_NE(judge_end(sh("while :; do :; done", limits), limits).find("hang"), std::string::npos);
  // Output is captured.
  const RunResult r = sh("echo out; echo err >&2");
  EXPECT_EQ(r.out, "out\n");
  EXPECT_EQ(r.err, "err\n");
}

TEST(FuzzJudge, TheMemoryLimitApplies) {
  RunLimits limits;
  limits.memory_bytes = 64L << 20;
  // dd's buffer of 256 MB cannot be allocated under 64 MB: dd fails (exit 1), it is not killed.
  const RunResult r = sh("dd if=/dev/zero of=/dev/null bs=256M count=1 2>/dev/null; echo $?", limits);
  EXPECT_EQ(judge_end(r, limits), "");
  EXPECT_NE(r.out, "0\n") << "dd allocated 256 MB under a 64 MB limit";
}

TEST(FuzzJudge, NonFiniteAndNullOutputsAreFindings) {
  EXPECT_EQ(check_output_text("load 54.0 %, infrastructure, financial"), "");
  EXPECT_NE(check_output_text("mean nan rad"), "");
  EXPECT_NE(check_output_text("max -inf"), "");
  EXPECT_NE(check_output_text("x: Infinity"), "");
  EXPECT_EQ(check_output_json(R"({"mean": 0.5, "frames": [1, 2], "faults": [], "x": {}})"), "");
  EXPECT_NE(check_output_json(R"({"mean": null})"), "");
  EXPECT_NE(check_output_json(R"({"a": {"b": [1, null]}})"), "");
  EXPECT_NE(check_output_json("{\"truncated\": "), "");
  EXPECT_NE(check_motion_file(testing::TempDir() + "/no_such.motion", model::Model{}), "");
}

TEST(FuzzInputs, BaseInputsAreValidAndMutationsReproducible) {
  static Corpus corpus;
  std::string error;
  ASSERT_TRUE(load_corpus(KUAVO_SHARED_DIR, corpus, error)) << error;
  EXPECT_EQ(check_motion_bytes(corpus.motion, corpus.robot), "");
  EXPECT_EQ(check_config_text(corpus.config_json, corpus.robot), "");
  for (const std::string& clip : corpus.bvh_clips) EXPECT_EQ(check_bvh_text(clip), "");
  for (std::uint64_t i = 0; i < 20; ++i) {
    Rng a(case_seed(7, i)), b(case_seed(7, i)), c(case_seed(8, i));
    EXPECT_EQ(mutate_bvh(corpus.bvh_clips[0], 20, a), mutate_bvh(corpus.bvh_clips[0], 20, b));
    EXPECT_EQ(mutate_motion(corpus.motion, a), mutate_motion(corpus.motion, b));
    EXPECT_EQ(mutate_config(corpus.config_json, a), mutate_config(corpus.config_json, b));
    EXPECT_NE(mutate_motion(corpus.motion, a), mutate_motion(corpus.motion, c));
  }
  EXPECT_NE(case_seed(1, 0), case_seed(1, 1));
  EXPECT_NE(case_seed(1, 0), case_seed(2, 0));
}

// The oracles judge what was accepted: the base inputs pass, and refused hostile inputs are
// not findings (they name their reason).
TEST(FuzzInputs, RefusalsAreNotFindingsButSilentOnesAre) {
  EXPECT_EQ(check_bvh_text("HIERARCHY\nROOT Hips\n{\n"), "");  // refused with a line number
  model::Model robot;
  ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot), model::ModelError::kOk);
  EXPECT_EQ(check_config_text("{\"buses\": 3}", robot), "");
  EXPECT_EQ(check_argument_tokens({"--stand", "nan"}), "");
  EXPECT_EQ(check_argument_tokens({"--stand", "5", "--seed", "1"}), "");
}

}  // namespace
}  // namespace kuavo::fuzz
