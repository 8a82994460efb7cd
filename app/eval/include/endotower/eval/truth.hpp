// Ground truth of a simulated recording: reader for `truth.jsonl` (docs/truth.md).
//
// Input: one JSON object per line. Required per line: `frame` (int, strictly
// increasing), `tools` (array). Per tool: `id`, `visible`, `tip_px`, `axis_deg`,
// `width_px`; optional `head_px`, `tip_mm`, `gesture`, `visible_fraction`.
// Optional per line (absent = empty/null): `gesture`, `regions` (each `id`,
// `polygon_px` with >= 3 points, optional `change`), `events`, `factors`, `light`,
// `speed_cm_s`. Members not listed are ignored (the schema only grows).
// Output: TruthFrame per line. Errors: "PATH:LINE: field 'tools[0].tip_px' ...".
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace endotower::eval {

struct Point2 {
    double x = 0, y = 0;
};
struct Point3 {
    double x = 0, y = 0, z = 0;
};

// A strip marker on a tool (book fig. 3.1), optional in truth.jsonl.
struct TruthMarker {
    int strip = 0;  // 0 = nearest the tip
    Point2 center_px;
    Point3 center_mm;
    bool visible = true;
};

struct TruthTool {
    int id = 0;
    bool visible = true;
    double visible_fraction = 1.0;
    Point2 tip_px, head_px;
    bool has_head = false;
    double axis_deg = 0;  // tip towards the incision point, atan2(dy, dx)
    double width_px = 0;  // apparent shaft width at the head
    std::optional<Point3> tip_mm;
    std::string gesture;  // single-tool gesture label, "" if not given
    std::vector<TruthMarker> markers;
};

struct TruthRegion {
    int id = 0;
    std::vector<Point2> polygon_px;
    std::string change = "none";
};

struct TruthFrame {
    std::int64_t frame = 0;
    std::vector<TruthTool> tools;
    std::optional<std::string> gesture;  // two-tool gesture, null when none
    std::vector<TruthRegion> regions;
    std::vector<std::string> events;
    // Factor name and level as text (bools "yes"/"no", numbers as written).
    std::vector<std::pair<std::string, std::string>> factors;
    double light = -1, speed_cm_s = -1;  // -1 when absent
};

// Parses one line; false with `error` = "field 'NAME' ..." on a malformed line.
bool parse_truth_line(const std::string& line, TruthFrame& out, std::string& error);
// Reads the whole file; errors are "PATH:LINE: what". Blank lines are skipped.
bool read_truth(const std::string& path, std::vector<TruthFrame>& out, std::string& error);

}  // namespace endotower::eval
