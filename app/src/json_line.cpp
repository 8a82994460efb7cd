#include "endotower/app/json_line.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace endotower::app {

void JsonLine::clear() {
    len_ = 0;
    depth_ = 0;
    overflow_ = false;
    first_.fill(true);
}

void JsonLine::put(std::string_view s) {
    if (overflow_ || len_ + s.size() > buf_.size()) {
        overflow_ = true;
        return;
    }
    std::memcpy(buf_.data() + len_, s.data(), s.size());
    len_ += s.size();
}

void JsonLine::put(char c) { put(std::string_view(&c, 1)); }

void JsonLine::separator() {
    if (depth_ == 0) return;
    if (!first_[depth_]) put(',');
    first_[depth_] = false;
}

void JsonLine::string(std::string_view s) {
    put('"');
    for (char c : s) {
        switch (c) {
            case '"': put("\\\""); break;
            case '\\': put("\\\\"); break;
            case '\n': put("\\n"); break;
            case '\r': put("\\r"); break;
            case '\t': put("\\t"); break;
            default:
                if (static_cast<unsigned char>(c) < 0x20) {
                    char esc[8];
                    const int n = std::snprintf(esc, sizeof esc, "\\u%04x", static_cast<unsigned>(c));
                    put(std::string_view(esc, static_cast<std::size_t>(n)));
                } else {
                    put(c);
                }
        }
    }
    put('"');
}

void JsonLine::key(std::string_view k) {
    separator();
    string(k);
    put(':');
}

void JsonLine::number(std::int64_t v) {
    char tmp[24];
    auto [end, ec] = std::to_chars(tmp, tmp + sizeof tmp, v);
    put(std::string_view(tmp, static_cast<std::size_t>(end - tmp)));
}

void JsonLine::number(double v) {
    if (!std::isfinite(v)) {
        put("null");
        return;
    }
    char tmp[32];
    // Shortest form that reads back to the same double.
    auto [end, ec] = std::to_chars(tmp, tmp + sizeof tmp, v);
    put(std::string_view(tmp, static_cast<std::size_t>(end - tmp)));
}

void JsonLine::open(char bracket) {
    put(bracket);
    if (depth_ + 1 < kMaxDepth) first_[++depth_] = true;
    else overflow_ = true;
}

void JsonLine::close(char bracket) {
    put(bracket);
    if (depth_ > 0) --depth_;
}

JsonLine& JsonLine::begin_object() {
    separator();
    open('{');
    return *this;
}

JsonLine& JsonLine::begin_object(std::string_view k) {
    key(k);
    open('{');
    return *this;
}

JsonLine& JsonLine::end_object() {
    close('}');
    return *this;
}

JsonLine& JsonLine::begin_array() {
    separator();
    open('[');
    return *this;
}

JsonLine& JsonLine::begin_array(std::string_view k) {
    key(k);
    open('[');
    return *this;
}

JsonLine& JsonLine::end_array() {
    close(']');
    return *this;
}

JsonLine& JsonLine::field(std::string_view k, std::int64_t v) {
    key(k);
    number(v);
    return *this;
}

JsonLine& JsonLine::field(std::string_view k, double v) {
    key(k);
    number(v);
    return *this;
}

JsonLine& JsonLine::field(std::string_view k, bool v) {
    key(k);
    put(v ? "true" : "false");
    return *this;
}

JsonLine& JsonLine::field(std::string_view k, std::string_view v) {
    key(k);
    string(v);
    return *this;
}

JsonLine& JsonLine::null_field(std::string_view k) {
    key(k);
    put("null");
    return *this;
}

JsonLine& JsonLine::value(std::int64_t v) {
    separator();
    number(v);
    return *this;
}

JsonLine& JsonLine::value(double v) {
    separator();
    number(v);
    return *this;
}

JsonLine& JsonLine::value(std::string_view v) {
    separator();
    string(v);
    return *this;
}

JsonLine& JsonLine::raw_members(std::string_view members) {
    if (members.empty()) return *this;
    separator();
    put(members);
    return *this;
}

}  // namespace endotower::app
