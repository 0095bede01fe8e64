// The HTML report: one folder whose index.html opens from disk (no server, no network) and
// shows the simulated robot dancing in 3D (Leju's meshes, decimated), the scaled human
// skeleton, the ground, the support polygon, the ZMP and the contact forces; play / pause,
// speed, a timeline with the repairs and any fall marked, plots linked to it, and the tables
// of the Markdown report. The page is tools/report/web/ (copied); this writes its data:
//   data/report.js   runs (name, description, fall, marks), tables, figures, text blocks
//   data/model.js    the kinematic tree exported from controllers/model (joint origins and
//                    axes, contact frames, peak torques) and, per body, its mesh and visual
//                    origin from Leju's URDF; plus a forward-kinematics check pose the page
//                    verifies against this model's FK (a console error if they disagree)
//   data/meshes.js   Leju's STL meshes, decimated (tools/report/mesh_decimate.h), base64
//   data/human.js    the human keypoints scaled to the robot (kuavo retarget --human-csv)
//   data/run_N.js    one run's replay, loaded when it is shown: little-endian float32 frames at
//                    kReplayRate_hz (base pose, joints, references, torques, contact forces, CoM,
//                    ZMP; the margin as the minimum and the torque ratio as the maximum over the
//                    ticks each frame stands for), base64 in a .js file (file:// forbids fetch)
// Offline code; allocates.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "controllers/model/model.h"

namespace kuavo::cli {

// The replay's frame rate: smooth to the eye, and a 4-minute dance is 6 000 frames (~3 MB).
inline constexpr double kReplayRate_hz = 25.0;
// Triangles per link after decimation: ~1 000 keeps the links recognizable; 33 meshes make
// ~0.6 MB of base64 (Leju's files hold 10 000 to 50 000 triangles each, 29 MB in all).
inline constexpr std::size_t kMeshTriangles = 1200;

// A span on a run's timeline (a point when end_s == start_s): a repair, a push, a fall.
struct TimelineMark {
  double start_s = 0.0, end_s = 0.0;
  std::string kind;   // "repair", "push", "fall"
  std::string label;  // what the page shows on hover
};

struct ReplayRun {
  std::string name, description;
  std::string log_csv;               // the simulator's CSV log (sim/motion_loop or sim/closed_loop header)
  bool fell = false;
  double fell_at_s = -1.0;
  bool follows_motion = false;       // the run dances the retargeted motion: repairs and human apply
  std::vector<TimelineMark> marks;   // pushes and the like (the fall and repairs are added)
};

struct HtmlTable {
  std::string title;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::string note;
};

struct HtmlReport {
  std::string title;
  std::string subtitle;                      // the pipeline in one line
  std::vector<ReplayRun> runs;
  std::vector<TimelineMark> repairs;         // in the motion's clock (= the simulator's)
  std::string human_csv;                     // empty: no skeleton
  std::vector<HtmlTable> tables;
  std::vector<std::pair<std::string, std::string>> figures;      // (file in the folder, caption)
  std::vector<std::pair<std::string, std::string>> text_blocks;  // (title, preformatted text)
};

// The repairs of a retarget report (its "dynamic" → "repairs" list); none for a geometric one.
bool read_repairs(const std::string& retarget_report_json, std::vector<TimelineMark>& out, std::string& error);

// Writes dir/index.html and its data (dir must exist). false with a message.
bool write_html_report(const model::Model& robot, const HtmlReport& report, const std::string& dir, std::string& error);

// The Markdown rendering of a table (the same table the page shows).
std::string markdown_table(const HtmlTable& t);

}  // namespace kuavo::cli
