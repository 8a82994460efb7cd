#include "json_fields.hpp"

namespace endotower::eval::detail {

std::string field_path(const std::string& prefix, const char* key) { return prefix + key; }

namespace {

const json* find(const json& o, const std::string& prefix, const char* key, std::string& error) {
    auto it = o.find(key);
    if (it == o.end()) {
        error = "missing field '" + field_path(prefix, key) + "'";
        return nullptr;
    }
    return &*it;
}

bool fail(const std::string& prefix, const char* key, const char* what, std::string& error) {
    error = "field '" + field_path(prefix, key) + "' " + what;
    return false;
}

bool to_point(const json& v, Point2& p) {
    if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number()) return false;
    p = {v[0].get<double>(), v[1].get<double>()};
    return true;
}

}  // namespace

bool get_int(const json& o, const std::string& prefix, const char* key, int& out, std::string& error) {
    std::int64_t v = 0;
    if (!get_int64(o, prefix, key, v, error)) return false;
    if (v < -2147483647 || v > 2147483647) return fail(prefix, key, "is out of range", error);
    out = static_cast<int>(v);
    return true;
}

bool get_int64(const json& o, const std::string& prefix, const char* key, std::int64_t& out,
               std::string& error) {
    const json* v = find(o, prefix, key, error);
    if (v == nullptr) return false;
    if (!v->is_number_integer()) return fail(prefix, key, "must be an integer", error);
    out = v->get<std::int64_t>();
    return true;
}

bool get_number(const json& o, const std::string& prefix, const char* key, double& out,
                std::string& error) {
    const json* v = find(o, prefix, key, error);
    if (v == nullptr) return false;
    if (!v->is_number()) return fail(prefix, key, "must be a number", error);
    out = v->get<double>();
    return true;
}

bool get_bool(const json& o, const std::string& prefix, const char* key, bool& out, std::string& error) {
    const json* v = find(o, prefix, key, error);
    if (v == nullptr) return false;
    if (!v->is_boolean()) return fail(prefix, key, "must be true or false", error);
    out = v->get<bool>();
    return true;
}

bool get_point(const json& o, const std::string& prefix, const char* key, Point2& out,
               std::string& error) {
    const json* v = find(o, prefix, key, error);
    if (v == nullptr) return false;
    if (!to_point(*v, out)) return fail(prefix, key, "must be [x, y] (two numbers)", error);
    return true;
}

bool get_polygon(const json& o, const std::string& prefix, const char* key, std::vector<Point2>& out,
                 std::string& error) {
    const json* v = find(o, prefix, key, error);
    if (v == nullptr) return false;
    out.clear();
    if (v->is_array()) {
        for (const json& p : *v) {
            Point2 q;
            if (!to_point(p, q)) break;
            out.push_back(q);
        }
    }
    if (!v->is_array() || out.size() != v->size() || out.size() < 3)
        return fail(prefix, key, "must be [[x, y], ...] with at least 3 points", error);
    return true;
}

bool opt_number(const json& o, const std::string& prefix, const char* key, double& out,
                std::string& error) {
    if (!o.contains(key)) return true;
    return get_number(o, prefix, key, out, error);
}

bool opt_point3(const json& o, const std::string& prefix, const char* key,
                std::optional<Point3>& out, std::string& error) {
    auto it = o.find(key);
    if (it == o.end() || it->is_null()) return true;
    const json& v = *it;
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() ||
        !v[2].is_number())
        return fail(prefix, key, "must be [x, y, z] (three numbers) or null", error);
    out = Point3{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
    return true;
}

bool get_array(const json& o, const std::string& prefix, const char* key, const json*& out,
               std::string& error) {
    out = find(o, prefix, key, error);
    if (out == nullptr) return false;
    if (!out->is_array()) return fail(prefix, key, "must be an array", error);
    return true;
}

bool parse_object(const std::string& line, json& out, std::string& error) {
    out = json::parse(line, nullptr, false);
    if (out.is_discarded()) {
        error = "not valid JSON";
        return false;
    }
    if (!out.is_object()) {
        error = "a line must be a JSON object";
        return false;
    }
    return true;
}

}  // namespace endotower::eval::detail

#include <fstream>

namespace endotower::eval::detail {

bool for_each_line(const std::string& path, const char* what,
                   const std::function<bool(const std::string&, std::string&)>& fn,
                   std::string& error) {
    std::ifstream in(path);
    if (!in) {
        error = std::string("cannot read ") + what + ": " + path;
        return false;
    }
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        std::string e;
        if (!fn(line, e)) {
            error = path + ":" + std::to_string(number) + ": " + e;
            return false;
        }
    }
    if (number == 0) {
        error = path + ": empty " + what;
        return false;
    }
    return true;
}

}  // namespace endotower::eval::detail
