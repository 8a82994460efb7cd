// Strict reading of JSON members with messages that name the field by its path,
// e.g. "field 'tools[1].tip_px' must be [x, y] (two numbers)". Internal to eval.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "endotower/eval/truth.hpp"

namespace endotower::eval::detail {

using nlohmann::json;

// "prefix" + "key": the field's path for messages ("" prefix for top level).
std::string field_path(const std::string& prefix, const char* key);

// Each reader: false with `error` set when the member is missing or of the wrong
// kind. The opt_ variants leave `out` untouched and succeed when the member is
// absent (and, for opt_point3, when it is null).
bool get_int(const json& o, const std::string& prefix, const char* key, int& out, std::string& error);
bool get_int64(const json& o, const std::string& prefix, const char* key, std::int64_t& out,
               std::string& error);
bool get_number(const json& o, const std::string& prefix, const char* key, double& out,
                std::string& error);
bool get_bool(const json& o, const std::string& prefix, const char* key, bool& out, std::string& error);
bool get_point(const json& o, const std::string& prefix, const char* key, Point2& out,
               std::string& error);
bool get_polygon(const json& o, const std::string& prefix, const char* key, std::vector<Point2>& out,
                 std::string& error);
bool opt_number(const json& o, const std::string& prefix, const char* key, double& out,
                std::string& error);
bool opt_point3(const json& o, const std::string& prefix, const char* key,
                std::optional<Point3>& out, std::string& error);
// A required array member; `out` points at it.
bool get_array(const json& o, const std::string& prefix, const char* key, const json*& out,
               std::string& error);

// Parses a line that must be a JSON object.
bool parse_object(const std::string& line, json& out, std::string& error);

}  // namespace endotower::eval::detail

#include <functional>

namespace endotower::eval::detail {

// Calls fn(line, error) for each non-blank line of the file; stops at the first false
// and reports "PATH:LINE: error". `what` names the file kind for "cannot read ...".
bool for_each_line(const std::string& path, const char* what,
                   const std::function<bool(const std::string&, std::string&)>& fn,
                   std::string& error);

}  // namespace endotower::eval::detail
