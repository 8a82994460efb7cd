// JsonLine: builds one JSON object in a fixed buffer, without allocating, for the
// per-frame trace. Keys and strings are escaped. If the buffer would overflow, the
// line is marked overflowed() and the writer drops the optional members that did not
// fit (the frame's core fields always come first).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace endotower::app {

class JsonLine {
public:
    static constexpr std::size_t kCapacity = 16 * 1024;
    static constexpr int kMaxDepth = 16;

    void clear();

    // Containers. begin_object(key)/begin_array(key) inside an object; the keyless
    // forms inside an array or at the top level.
    JsonLine& begin_object();
    JsonLine& begin_object(std::string_view key);
    JsonLine& end_object();
    JsonLine& begin_array();
    JsonLine& begin_array(std::string_view key);
    JsonLine& end_array();

    // Members of an object.
    JsonLine& field(std::string_view key, std::int64_t v);
    JsonLine& field(std::string_view key, int v) { return field(key, static_cast<std::int64_t>(v)); }
    JsonLine& field(std::string_view key, double v);  // NaN/inf -> null
    JsonLine& field(std::string_view key, bool v);
    JsonLine& field(std::string_view key, std::string_view v);
    JsonLine& field(std::string_view key, const char* v) { return field(key, std::string_view(v)); }
    JsonLine& null_field(std::string_view key);

    // Elements of an array.
    JsonLine& value(std::int64_t v);
    JsonLine& value(double v);
    JsonLine& value(std::string_view v);

    // Raw members already formatted as JSON ("\"a\":1,\"b\":2"), appended to the
    // current object. Used to splice in a stage's trace fields.
    JsonLine& raw_members(std::string_view members);

    std::string_view view() const { return {buf_.data(), len_}; }
    bool overflowed() const { return overflow_; }

private:
    void put(std::string_view s);
    void put(char c);
    void separator();
    void open(char bracket);   // '{' or '[': one level deeper
    void close(char bracket);
    void key(std::string_view k);
    void string(std::string_view s);
    void number(std::int64_t v);
    void number(double v);

    std::array<char, kCapacity> buf_{};
    std::size_t len_ = 0;
    std::array<bool, kMaxDepth> first_{};  // no member written yet at this depth
    int depth_ = 0;
    bool overflow_ = false;
};

}  // namespace endotower::app
