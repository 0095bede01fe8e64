// The closed-loop check's repair ladder (`kuavo retarget`'s verification, retarget_dynamic.cpp):
// where the retargeted motion falls in the check, which frames are repaired and how, and when
// the check gives up a run instead (pushed over, or fallen over feet already held).
#pragma once

#include <utility>
#include <vector>

namespace kuavo::cli {

struct VerifyLadder {
  double gain = 0.5;      // the first fall in a range scales its gestures by this
  double before_s = 2.0;  // the range: [fall − before_s, fall + after_s)
  double after_s = 0.3;
};

// A fall's repair: the dance-clock frames [a, b) = [fall − before_s, fall + after_s) within
// the dance, scaled by gain, or by 0 and with calm steps (mocap::RepairConfig::calm_*) where a
// range of an earlier round overlaps, and with both feet held down over it where two do.
struct VerifyRange {
  int a = 0, b = 0;
  double gain = 1.0;
  bool calm_steps = false;  // a second fall there: calm steps too
  bool hold = false;        // a third: both feet down over the range
};

// The repair of a fall at fell_at_s (the output motion's clock, lead_frames of lead-in before
// the dance's dance_frames); its range is appended to `scaled` (the earlier rounds').
// false if nothing of the dance lies there (a fall in the lead-in or the tail).
bool verification_range(double fell_at_s, int lead_frames, int dance_frames, double rate_hz, const VerifyLadder& ladder,
                        std::vector<std::pair<int, int>>& scaled, VerifyRange& out);

// Whether the check gives up a pushed run that fell at fell_at_s: the push (push_start_s) came
// before the fall and within the range the fall would repair (at most before_s before it: the
// push tipped it over, not the motion seconds later), and the ladder's next rung there is
// holding both feet down. `scaled` is left as it is.
bool gives_up_pushed_run(double push_start_s, double fell_at_s, int lead_frames, int dance_frames, double rate_hz,
                         const VerifyLadder& ladder, const std::vector<std::pair<int, int>>& scaled);

// Whether the check gives up a run with the show set's model errors (pushed or not) that fell
// at fell_at_s where an earlier round already held both feet down: the range the fall would
// repair overlaps one that verification_range made a hold (two earlier ranges over it when it
// came). The ladder has no stronger rung; holding again only moves the held range, and the
// round's remaining runs go unchecked (cmu_05_07 at 50d3af2: one show-set seed fell at
// 8.8-10.8 s in rounds 6-8 and 10-16 over held feet, and the round written fell in another at
// 4.0 s). The runs without model errors are never given up. `scaled` is left as it is.
bool gives_up_held_run(double fell_at_s, int lead_frames, int dance_frames, double rate_hz, const VerifyLadder& ladder,
                       const std::vector<std::pair<int, int>>& scaled);

}  // namespace kuavo::cli
