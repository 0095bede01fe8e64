// Seeded hostile inputs for the fuzz harness (issue 22) and the oracles that judge what the
// parsers and programs accepted. Every case is drawn from its own generator seeded with
// case_seed(seed, index), so one case reproduces alone (kuavo_fuzz --seed S --first-case N).
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "controllers/model/model.h"

namespace kuavo::fuzz {

using Rng = std::mt19937_64;

// splitmix64 of (seed, index): independent, reproducible per-case seeds.
std::uint64_t case_seed(std::uint64_t seed, std::uint64_t index);

// The valid inputs every mutation starts from.
struct Corpus {
  model::Model robot;
  std::vector<std::string> bvh_names, bvh_clips;  // ../shared/mocap/*.bvh, whole texts
  std::vector<std::uint8_t> motion;  // a valid s45 motion: 60 frames standing, the arms swaying
  std::string config_json;           // a valid drivers overlay that sets every key
};
// false with error when the shared clips cannot be read or the model not built.
bool load_corpus(const std::string& shared_dir, Corpus& corpus, std::string& error);

// A shared clip cut to its header and 1..max_frames frames ("Frames:" kept consistent), then
// 1..3 mutations: bytes flipped, inserted or deleted, numbers replaced by hostile ones (nan,
// 1e308, 1e999, -0, huge integers, empty), line endings converted, a byte-order mark, lines
// duplicated or dropped, Frames / Frame Time forged, garbage appended.
std::string mutate_bvh(const std::string& clip, int max_frames, Rng& rng);
// A valid motion with 1..3 mutations (special values, small shifts across a limit, random
// bytes, appended data or the file twice, a forged frame count, header fields) and both
// checksums recomputed, so every mutation reaches the frame checks.
std::vector<std::uint8_t> mutate_motion(const std::vector<std::uint8_t>& good, Rng& rng);
// The overlay with 1..3 mutations: a leaf set to a hostile value (1e308, -1, 0, 0.5, 1e-320,
// 1e999, a string, null, an array, an object, a NUL-bearing path), a key dropped, added,
// misspelt or given twice, deep nesting, or text-level damage (truncation, bytes).
std::string mutate_config(const std::string& good, Rng& rng);

// A command line: `fixed` tokens kept first (they bound the run: e.g. --check, a short
// --duration), `base` mutated 1..2 times with `options` (the program's own and a few
// strangers) and `values` (valid and hostile): values replaced, tokens dropped (a missing
// value), options inserted or repeated, tokens swapped.
std::vector<std::string> mutate_command_line(const std::vector<std::string>& fixed, const std::vector<std::string>& base,
                                             const std::vector<std::string>& options,
                                             const std::vector<std::string>& values, Rng& rng);

// --- Oracles: "" when the input was handled soundly, otherwise what went wrong ---

// parse_bvh on the text: no exception; if it accepts, every value finite and inside the
// bounds of tools/mocap/bvh.h, the frame time and count inside theirs.
std::string check_bvh_text(const std::string& text);
// The motion reader on the bytes: no exception; if it accepts, exactly the header and its
// frames, every value finite, a unit quaternion, the base on the stage, every joint within
// the model's limits (checked here, not by calling the reader's own rule).
std::string check_motion_bytes(const std::vector<std::uint8_t>& bytes, const model::Model& robot);
// apply_drivers_json + validate_drivers_config: no exception; if accepted, every number
// finite and bus loads at most 70 %.
std::string check_config_text(const std::string& text, const model::Model& robot);
// The strict argument parser on tokens drawn from `values` for a table of every kind: no
// exception; if accepted, every number inside its declared range.
std::string check_argument_tokens(const std::vector<std::string>& tokens);

// A program's output after exit 0: no "nan"/"inf" word, and in JSON no null.
std::string check_output_text(const std::string& text);
std::string check_output_json(const std::string& text);
// A motion file a program wrote or accepted, by the rules of check_motion_bytes.
std::string check_motion_file(const std::string& path, const model::Model& robot);

// The hostile values the mutators draw from (also the command-line values).
const std::vector<std::string>& hostile_numbers();

}  // namespace kuavo::fuzz
