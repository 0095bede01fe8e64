#include "tools/mocap/bvh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace kuavo::mocap {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

struct Token {
  std::string_view text;
  int line;
};

// Splits into whitespace-separated tokens with their 1-based line numbers. LF, CRLF and a
// lone CR (classic Mac OS) each end a line, so every convention and any mix of them reads the
// same and motion rows break where the file's lines do. Braces are tokens even when glued to
// a word ("{" after a name without a space happens in hand-edited files).
class Lexer {
 public:
  explicit Lexer(std::string_view text) : text_(text) {}

  bool next(Token& t) {
    skip_space();
    if (pos_ >= text_.size()) return false;
    const std::size_t start = pos_;
    if (text_[pos_] == '{' || text_[pos_] == '}') {
      ++pos_;
    } else {
      while (pos_ < text_.size() && !is_space(text_[pos_]) && text_[pos_] != '{' && text_[pos_] != '}') ++pos_;
    }
    t = {text_.substr(start, pos_ - start), line_};
    return true;
  }
  // Rest of the current line (for names with spaces, e.g. "JOINT Left Arm").
  std::string_view rest_of_line() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t')) ++pos_;
    const std::size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r' && text_[pos_] != '{') ++pos_;
    std::string_view s = text_.substr(start, pos_ - start);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
  }
  int line() const { return line_; }
  std::size_t pos() const { return pos_; }
  std::string_view text() const { return text_; }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }
  void skip_space() {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      const bool lone_cr = text_[pos_] == '\r' && (pos_ + 1 >= text_.size() || text_[pos_ + 1] != '\n');
      if (text_[pos_] == '\n' || lone_cr) ++line_;
      ++pos_;
    }
  }
  std::string_view text_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

bool to_double(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(v);
}

bool to_int(std::string_view s, long& v) {
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parse_channel(std::string_view s, BvhChannel& c) {
  struct Name {
    const char* text;
    BvhChannel channel;
  };
  static constexpr Name kNames[] = {{"Xposition", BvhChannel::kXposition}, {"Yposition", BvhChannel::kYposition},
                                    {"Zposition", BvhChannel::kZposition}, {"Xrotation", BvhChannel::kXrotation},
                                    {"Yrotation", BvhChannel::kYrotation}, {"Zrotation", BvhChannel::kZrotation}};
  for (const Name& n : kNames) {
    const std::string_view t(n.text);
    if (s.size() != t.size()) continue;
    bool same = true;  // case-insensitive: "XPOSITION" and "xrotation" occur in the wild
    for (std::size_t i = 0; i < s.size() && same; ++i) same = std::tolower(s[i]) == std::tolower(t[i]);
    if (same) {
      c = n.channel;
      return true;
    }
  }
  return false;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

constexpr const char* kLengthReason = "100 m in millimetres: no capture volume or bone is that large";

std::string quote(std::string_view s) {
  std::string out = "'";
  for (char c : s.substr(0, 40)) out += (c >= 32 && c < 127) ? c : '?';
  if (s.size() > 40) out += "...";
  return out + "'";
}

class Parser {
 public:
  Parser(std::string_view text, Bvh& out, std::string& error) : lex_(text), out_(out), error_(error) {}

  bool run() {
    out_ = Bvh{};
    Token t;
    if (!lex_.next(t)) return fail(1, "empty file (expected HIERARCHY)");
    if (t.text != "HIERARCHY") return fail(t.line, "expected HIERARCHY, found " + quote(t.text));
    if (!hierarchy()) return false;
    if (!motion()) return false;
    decide_position_modes();
    return true;
  }

 private:
  bool fail(int line, const std::string& what) {
    error_ = "line " + std::to_string(line) + ": " + what;
    return false;
  }

  bool expect(std::string_view word, Token& t) {
    if (!lex_.next(t)) return fail(lex_.line(), "unexpected end of file (expected " + std::string(word) + ")");
    if (t.text != word) return fail(t.line, "expected " + std::string(word) + ", found " + quote(t.text));
    return true;
  }

  bool offset(BvhJoint& j) {
    Token t;
    if (!expect("OFFSET", t)) return false;
    for (int k = 0; k < 3; ++k) {
      if (!lex_.next(t)) return fail(lex_.line(), "unexpected end of file in OFFSET of " + quote(j.name));
      if (!to_double(t.text, j.offset[k]))
        return fail(t.line, "OFFSET of " + quote(j.name) + " needs 3 finite numbers, found " + quote(t.text));
      if (std::abs(j.offset[k]) > kBvhMaxLength)
        return fail(t.line, "OFFSET of " + quote(j.name) + " " + quote(t.text) + " exceeds " + number(kBvhMaxLength) +
                                " file units (" + kLengthReason + ")");
    }
    return true;
  }

  bool channels(BvhJoint& j) {
    Token t;
    if (!expect("CHANNELS", t)) return false;
    long n = 0;
    if (!lex_.next(t) || !to_int(t.text, n) || n < 0 || n > 6)
      return fail(t.line, "CHANNELS of " + quote(j.name) + " needs a count 0..6, found " + quote(t.text));
    for (long k = 0; k < n; ++k) {
      BvhChannel c{};
      if (!lex_.next(t)) return fail(lex_.line(), "unexpected end of file in CHANNELS of " + quote(j.name));
      if (!parse_channel(t.text, c))
        return fail(t.line, "unknown channel " + quote(t.text) + " in " + quote(j.name) +
                                " (expected X/Y/Z position or rotation)");
      for (BvhChannel seen : j.channels)
        if (seen == c) return fail(t.line, "channel " + quote(t.text) + " repeated in " + quote(j.name));
      j.channels.push_back(c);
    }
    j.first_column = out_.channel_count;
    out_.channel_count += static_cast<int>(n);
    return true;
  }

  // ROOT name { OFFSET CHANNELS (JOINT ... | End Site {...})* } — iterative, so deeply
  // nested hostile input cannot overflow the stack.
  bool hierarchy() {
    Token t;
    if (!lex_.next(t)) return fail(lex_.line(), "unexpected end of file (expected ROOT)");
    if (t.text != "ROOT") return fail(t.line, "expected ROOT, found " + quote(t.text));
    std::vector<int> stack;
    if (!open_joint(-1, t.line, false)) return false;
    stack.push_back(0);
    while (!stack.empty()) {
      if (!lex_.next(t))
        return fail(lex_.line(),
                    "unexpected end of file inside joint " + quote(out_.joints[stack.back()].name) + " (missing '}')");
      if (t.text == "}") {
        stack.pop_back();
      } else if (t.text == "JOINT") {
        if (out_.joints[stack.back()].end_site) return fail(t.line, "an End Site cannot have children");
        if (!open_joint(stack.back(), t.line, false)) return false;
        stack.push_back(static_cast<int>(out_.joints.size()) - 1);
      } else if (t.text == "End") {
        Token site;
        if (!lex_.next(site) || site.text != "Site") return fail(t.line, "expected 'End Site'");
        if (!open_joint(stack.back(), t.line, true)) return false;
        stack.push_back(static_cast<int>(out_.joints.size()) - 1);
      } else if (t.text == "ROOT") {
        return fail(t.line, "only one ROOT is supported (a second ROOT appears before MOTION)");
      } else {
        return fail(t.line, "expected JOINT, End Site or '}', found " + quote(t.text));
      }
    }
    return true;
  }

  bool open_joint(int parent, int line, bool end_site) {
    if (static_cast<int>(out_.joints.size()) >= kBvhMaxJoints)
      return fail(line, "more than " + std::to_string(kBvhMaxJoints) + " joints");
    BvhJoint j;
    j.parent = parent;
    j.line = line;
    j.end_site = end_site;
    if (end_site) {
      j.name = out_.joints[parent].name + "_End";
    } else {
      const std::string_view name = lex_.rest_of_line();
      if (name.empty()) return fail(line, "joint without a name");
      j.name = std::string(name);
    }
    Token t;
    if (!expect("{", t)) return false;
    if (!offset(j)) return false;
    if (!end_site && !channels(j)) return false;
    out_.joints.push_back(std::move(j));
    return true;
  }

  bool motion() {
    Token t;
    if (!lex_.next(t)) return fail(lex_.line(), "unexpected end of file (expected MOTION)");
    if (t.text != "MOTION") return fail(t.line, "expected MOTION after the hierarchy, found " + quote(t.text));
    if (!expect("Frames:", t)) return false;
    long frames = 0;
    if (!lex_.next(t) || !to_int(t.text, frames) || frames < 1)
      return fail(t.line, "Frames: needs a positive integer (a motion has at least one frame), found " + quote(t.text));
    const int frames_line = t.line;
    Token w1, w2;
    if (!lex_.next(w1) || w1.text != "Frame" || !lex_.next(w2) || w2.text != "Time:")
      return fail(w1.line, "expected 'Frame Time:'");
    double dt = 0.0;
    if (!lex_.next(t) || !to_double(t.text, dt) || !(dt > 0.0))
      return fail(t.line, "Frame Time: needs a positive number of seconds, found " + quote(t.text));
    if (dt < kBvhMinFrameTime_s)
      return fail(t.line, "Frame Time: " + quote(t.text) + " s is below " + number(kBvhMinFrameTime_s) +
                              " s (10 kHz: faster than any motion capture records)");
    if (dt > kBvhMaxFrameTime_s)
      return fail(t.line, "Frame Time: " + quote(t.text) + " s is above " + number(kBvhMaxFrameTime_s) +
                              " s (4 Hz: slower, a dance's beat is no longer sampled)");
    if (static_cast<double>(frames - 1) * dt > kBvhMaxDuration_s)
      return fail(frames_line, "Frames: " + std::to_string(frames) + " at Frame Time " + number(dt) + " s last " +
                                   number(static_cast<double>(frames - 1) * dt) + " s, more than " +
                                   number(kBvhMaxDuration_s) + " s (one dance piece per motion file)");
    const long columns = out_.channel_count;
    if (columns > 0 && frames > kBvhMaxValues / columns)
      return fail(frames_line, "Frames: " + std::to_string(frames) + " is too large for this parser");
    out_.frame_count = static_cast<int>(frames);
    out_.frame_time_s = dt;
    // Reserve only what the text can hold (each value is at least 2 characters), so a
    // lying Frames: count cannot make us allocate gigabytes.
    const std::size_t remaining = lex_.text().size() - lex_.pos();
    out_.motion.reserve(std::min<std::size_t>(static_cast<std::size_t>(frames * columns), remaining / 2 + 1));
    // Rows: exactly one frame per line; line numbers tell where rows break.
    long row = 0, in_row = 0;
    int row_line = -1, last_row_line = -1;
    while (lex_.next(t)) {
      if (columns == 0) return fail(t.line, "motion values but the hierarchy declares no channels");
      if (in_row == 0) {
        if (t.line == last_row_line)
          return fail(t.line, "motion row " + std::to_string(row - 1) + " has more than " + std::to_string(columns) +
                                  " values");
        if (row >= frames) return fail(t.line, "more motion rows than 'Frames: " + std::to_string(frames) + "'");
        row_line = t.line;
      } else if (t.line != row_line) {
        return fail(row_line, "motion row " + std::to_string(row) + " has " + std::to_string(in_row) +
                                  " values, expected " + std::to_string(columns));
      }
      double v = 0.0;
      if (!to_double(t.text, v)) return fail(t.line, "motion value " + quote(t.text) + " is not a finite number");
      if (!value_in_bounds(in_row, v, t, row)) return false;
      out_.motion.push_back(v);
      if (++in_row == columns) {
        in_row = 0;
        ++row;
        last_row_line = row_line;
      }
    }
    if (in_row != 0)
      return fail(row_line, "motion row " + std::to_string(row) + " has " + std::to_string(in_row) +
                                " values, expected " + std::to_string(columns) + " (file truncated?)");
    if (columns > 0 && row != frames)
      return fail(lex_.line(), "file ends after " + std::to_string(row) + " of " + std::to_string(frames) +
                                   " motion rows (truncated?)");
    return true;
  }

  // Position channels within kBvhMaxLength, rotations within kBvhMaxAngle_deg.
  bool value_in_bounds(long column, double v, const Token& t, long row) {
    if (column_joint_.empty()) {  // column → joint, built once
      column_joint_.resize(static_cast<std::size_t>(out_.channel_count));
      for (std::size_t i = 0; i < out_.joints.size(); ++i)
        for (std::size_t k = 0; k < out_.joints[i].channels.size(); ++k)
          column_joint_[static_cast<std::size_t>(out_.joints[i].first_column) + k] = static_cast<int>(i);
    }
    const BvhJoint& j = out_.joints[static_cast<std::size_t>(column_joint_[static_cast<std::size_t>(column)])];
    const BvhChannel c = j.channels[static_cast<std::size_t>(column - j.first_column)];
    const bool position = static_cast<int>(c) < 3;
    const double bound = position ? kBvhMaxLength : kBvhMaxAngle_deg;
    if (std::abs(v) <= bound) return true;
    return fail(t.line, "motion row " + std::to_string(row) + ", " + quote(j.name) + " " + channel_name(c) + " " +
                            quote(t.text) + " exceeds " + number(bound) +
                            (position ? std::string(" file units (") + kLengthReason + ")"
                                      : std::string(" degrees (2 778 turns: no dance turns that far)")));
  }

  // A position channel is absolute when its values sit around OFFSET rather than around 0
  // (MotionBuilder-style); otherwise it is added to OFFSET (CMU, CC_Base root).
  void decide_position_modes() {
    if (out_.frame_count == 0) return;
    for (BvhJoint& j : out_.joints) {
      Vec3 mean = Vec3::Zero();
      bool has = false;
      for (std::size_t k = 0; k < j.channels.size(); ++k) {
        const int axis = static_cast<int>(j.channels[k]);
        if (axis > 2) continue;
        has = true;
        double s = 0.0;
        for (int f = 0; f < out_.frame_count; ++f) s += out_.row(f)[j.first_column + k];
        mean[axis] = s / out_.frame_count;
      }
      const double off = j.offset.norm();
      j.position_absolute = has && off > 0.0 && (mean - j.offset).norm() < 0.5 * off;
    }
  }

  Lexer lex_;
  Bvh& out_;
  std::string& error_;
  std::vector<int> column_joint_;
};

Mat3 axis_rotation(int axis, double deg) {
  return Eigen::AngleAxisd(deg * kDegToRad, Vec3::Unit(axis)).toRotationMatrix();
}

void local_transform(const BvhJoint& j, const double* row, Vec3& t, Mat3& r) {
  t = j.offset;
  r.setIdentity();
  bool first_position = true;
  for (std::size_t k = 0; k < j.channels.size(); ++k) {
    const int c = static_cast<int>(j.channels[k]);
    const double v = row ? row[j.first_column + k] : 0.0;
    if (c < 3) {
      if (first_position && j.position_absolute) t.setZero();
      first_position = false;
      t[c] += v;
    } else {
      r = r * axis_rotation(c - 3, v);
    }
  }
  if (!row && j.position_absolute) t = j.offset;
}

}  // namespace

int Bvh::find(std::string_view name) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return static_cast<int>(i);
  return -1;
}

bool parse_bvh(std::string_view text, Bvh& out, std::string& error) {
  // A UTF-8 byte-order mark (Windows editors write one) is not part of the text. UTF-16 and
  // UTF-32 are not BVH: say so instead of failing on the NUL bytes.
  constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";
  if (text.substr(0, 3) == kUtf8Bom) text.remove_prefix(3);
  if (text.substr(0, 2) == "\xFF\xFE" || text.substr(0, 2) == "\xFE\xFF" ||
      text.substr(0, 4) == std::string_view("\x00\x00\xFE\xFF", 4)) {
    out = Bvh{};
    error = "line 1: the file is UTF-16 or UTF-32 (byte-order mark); save it as UTF-8 or ASCII";
    return false;
  }
  Parser p(text, out, error);
  try {
    if (p.run()) return true;
  } catch (const std::exception& e) {  // only std::bad_alloc can get here
    error = std::string("out of memory while parsing: ") + e.what();
  }
  out = Bvh{};
  return false;
}

bool load_bvh_file(const std::string& path, Bvh& out, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = path + ": cannot open";
    return false;
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  if (!parse_bvh(ss.str(), out, error)) {
    error = path + ": " + error;
    return false;
  }
  return true;
}

void bvh_pose(const Bvh& bvh, int frame, std::vector<Vec3>& position, std::vector<Mat3>& rotation) {
  const std::size_t n = bvh.joints.size();
  position.resize(n);
  rotation.resize(n);
  const double* row = bvh.row(frame);
  for (std::size_t i = 0; i < n; ++i) {
    const BvhJoint& j = bvh.joints[i];
    Vec3 t;
    Mat3 r;
    local_transform(j, row, t, r);
    if (j.parent < 0) {
      position[i] = t;
      rotation[i] = r;
    } else {
      position[i] = position[j.parent] + rotation[j.parent] * t;
      rotation[i] = rotation[j.parent] * r;
    }
  }
}

void bvh_rest_pose(const Bvh& bvh, std::vector<Vec3>& position) {
  position.resize(bvh.joints.size());
  for (std::size_t i = 0; i < bvh.joints.size(); ++i) {
    const BvhJoint& j = bvh.joints[i];
    position[i] = j.parent < 0 ? Vec3(j.offset) : Vec3(position[j.parent] + j.offset);
  }
}

const char* channel_name(BvhChannel c) {
  switch (c) {
    case BvhChannel::kXposition:
      return "Xposition";
    case BvhChannel::kYposition:
      return "Yposition";
    case BvhChannel::kZposition:
      return "Zposition";
    case BvhChannel::kXrotation:
      return "Xrotation";
    case BvhChannel::kYrotation:
      return "Yrotation";
    case BvhChannel::kZrotation:
      return "Zrotation";
  }
  return "?";
}

std::string write_bvh(const Bvh& bvh) {
  std::string s = "HIERARCHY\n";
  char buf[96];
  std::vector<int> depth(bvh.joints.size(), 0);
  auto indent = [&](int d) { s.append(static_cast<std::size_t>(d), '\t'); };
  auto close_to = [&](int from_depth, int to_depth) {
    for (int d = from_depth; d >= to_depth; --d) {
      indent(d);
      s += "}\n";
    }
  };
  int open_depth = -1;
  for (std::size_t i = 0; i < bvh.joints.size(); ++i) {
    const BvhJoint& j = bvh.joints[i];
    depth[i] = j.parent < 0 ? 0 : depth[j.parent] + 1;
    if (open_depth >= depth[i]) close_to(open_depth, depth[i]);
    indent(depth[i]);
    if (j.parent < 0)
      s += "ROOT " + j.name + "\n";
    else if (j.end_site)
      s += "End Site\n";
    else
      s += "JOINT " + j.name + "\n";
    indent(depth[i]);
    s += "{\n";
    indent(depth[i] + 1);
    std::snprintf(buf, sizeof buf, "OFFSET %.10g %.10g %.10g\n", j.offset.x(), j.offset.y(), j.offset.z());
    s += buf;
    if (!j.end_site) {
      indent(depth[i] + 1);
      s += "CHANNELS " + std::to_string(j.channels.size());
      for (BvhChannel c : j.channels) s += std::string(" ") + channel_name(c);
      s += "\n";
    }
    open_depth = depth[i];
  }
  if (open_depth >= 0) close_to(open_depth, 0);
  s += "MOTION\nFrames: " + std::to_string(bvh.frame_count) + "\n";
  std::snprintf(buf, sizeof buf, "Frame Time: %.10g\n", bvh.frame_time_s);
  s += buf;
  for (int f = 0; f < bvh.frame_count; ++f) {
    const double* row = bvh.row(f);
    for (int c = 0; c < bvh.channel_count; ++c) {
      std::snprintf(buf, sizeof buf, c ? " %.10g" : "%.10g", row[c]);
      s += buf;
    }
    s += "\n";
  }
  return s;
}

}  // namespace kuavo::mocap
