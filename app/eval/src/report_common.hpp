// Formatting shared by the summary, the markdown report and the plots. Internal.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "endotower/eval/tool_metrics.hpp"

namespace endotower::eval::detail {

// printf into a std::string.
template <typename... A>
std::string fmt(const char* f, A... a) {
    char buf[512];
    std::snprintf(buf, sizeof buf, f, a...);
    return buf;
}

// The book's name for a scenario factor (table 4.1): "speed" -> "Tool speed (cm/s)".
std::string factor_title(const std::string& factor);
// The levels in display order: speed, light, distractors (table 4.1), then other
// factors by name; levels by their first number ("0-4" < "4-8" < ">8"), then text.
std::vector<LevelScore> ordered_levels(const std::vector<LevelScore>& levels);
// "87.5" for 0.875.
std::string pct(double fraction);

}  // namespace endotower::eval::detail
