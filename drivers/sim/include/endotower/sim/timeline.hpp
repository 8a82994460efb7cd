// Event timeline: the scripted handle input of a simulation run, a text file.
//
//   # comment                     blank lines and '#' comments are ignored
//   frame 12   press              at the capture of frame 12 (0-based), button 0
//   frame 20   release 0
//   t 1.250    wheel +2           1.250 s after the first frame, 2 detents
//   t 2.0      press 1            button 1
//   frame 30   region 100,80 220,84 210,190 96,180
//                                 marks a tissue region (polygon in that frame's pixels)
//   frame 40   region 10,10 90,10 90,70 overlay=image:logo.png
//                                 ... with an anchored overlay (docs/regions.md)
//
// "frame N" or "t SECONDS" (>= 0), then press|release [BUTTON 0-7] or wheel DELTA
// (non-zero integer, -1000..1000) or region X,Y X,Y X,Y ... (3 to 16 vertices, finite
// numbers; regions get ids in file order). Errors name the file, line and field.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "endotower/hal/control_input.hpp"

namespace endotower::sim {

struct TimelinePoint {
    double x = 0, y = 0;
};

struct TimelineEntry {
    enum class Anchor { kFrame, kTime };
    Anchor anchor = Anchor::kFrame;
    std::int64_t frame = 0;     // with kFrame
    hal::Nanos offset_ns = 0;   // with kTime, from the first frame's capture
    hal::ControlEvent event{};  // time_ns is filled when the timeline is scheduled
    std::vector<TimelinePoint> region;  // a region mark when not empty (event unused)
    std::string overlay;                // the region's overlay=KIND text, "" = not given
    int line = 0;               // 1-based line in the file, for messages
};

struct Timeline {
    std::vector<TimelineEntry> entries;  // in file order
};

// Parses timeline text; `name` is used in messages. On error returns false and sets
// `error` to "NAME:LINE: what is wrong".
bool parse_timeline(std::string_view text, std::string_view name, Timeline& out,
                    std::string& error);
// Reads and parses a file (missing/unreadable file: error names the path).
bool load_timeline(const std::string& path, Timeline& out, std::string& error);

}  // namespace endotower::sim
