// Reader for the Sznitman et al. laparoscopy annotations (train.xml / test.xml). The
// file is a flat, tiny XML dialect; a hand tokenizer keeps line numbers for messages
// and refuses anything it does not expect (e.g. the "<frame><frame>" of a bad edit).
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include "endotower/eval/annotations.hpp"

namespace endotower::eval {

namespace {

struct Token {
    enum Kind { kOpen, kClose, kText, kEnd } kind = kEnd;
    std::string text;  // tag name or trimmed text
    int line = 0;
};

class Tokenizer {
public:
    explicit Tokenizer(std::string s) : s_(std::move(s)) {}

    // False on a malformed tag; `error` says what.
    bool next(Token& t, std::string& error) {
        for (;;) {
            skip_space();
            t.line = line_;
            if (pos_ >= s_.size()) {
                t.kind = Token::kEnd;
                return true;
            }
            if (s_[pos_] != '<') {
                const std::size_t end = s_.find('<', pos_);
                t.kind = Token::kText;
                t.text = s_.substr(pos_, end == std::string::npos ? std::string::npos : end - pos_);
                advance_to(end == std::string::npos ? s_.size() : end);
                while (!t.text.empty() && std::isspace(static_cast<unsigned char>(t.text.back())))
                    t.text.pop_back();
                return true;
            }
            const std::size_t close = s_.find('>', pos_);
            if (close == std::string::npos) {
                error = "unterminated tag";
                return false;
            }
            std::string tag = s_.substr(pos_ + 1, close - pos_ - 1);
            advance_to(close + 1);
            if (!tag.empty() && (tag[0] == '?' || tag[0] == '!')) continue;  // declaration, comment
            t.kind = tag[0] == '/' ? Token::kClose : Token::kOpen;
            t.text = t.kind == Token::kClose ? tag.substr(1) : tag;
            return true;
        }
    }

private:
    void skip_space() {
        while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) {
            if (s_[pos_] == '\n') ++line_;
            ++pos_;
        }
    }
    void advance_to(std::size_t p) {
        for (; pos_ < p; ++pos_)
            if (s_[pos_] == '\n') ++line_;
    }
    std::string s_;
    std::size_t pos_ = 0;
    int line_ = 1;
};

bool parse_numbers(const std::string& text, std::vector<double>& out) {
    out.clear();
    std::istringstream in(text);
    std::string word;
    while (in >> word) {
        char* end = nullptr;
        const double v = std::strtod(word.c_str(), &end);
        if (end == word.c_str() || *end != 0) return false;
        out.push_back(v);
    }
    return true;
}

}  // namespace

int SznitmanAnnotations::tool_frames() const {
    int n = 0;
    for (const SznitmanFrame& f : frames) n += static_cast<int>(f.tools.size());
    return n;
}

bool read_sznitman(const std::string& path, SznitmanAnnotations& out, std::string& error) {
    std::ifstream in(path);
    if (!in) {
        error = "cannot read annotations: " + path;
        return false;
    }
    std::stringstream buf;
    buf << in.rdbuf();
    Tokenizer tok(buf.str());
    out = SznitmanAnnotations{};
    std::set<int> seen;
    Token t;
    std::string what;
    auto fail = [&](int line, const std::string& m) {
        error = path + ":" + std::to_string(line) + ": " + m;
        return false;
    };
    // Reads "<name> TEXT </name>" after the opening tag; returns the text.
    auto element_text = [&](const std::string& name, std::string& text, int& line) {
        Token body, close;
        if (!tok.next(body, what)) return fail(body.line, what);
        line = body.line;
        if (body.kind != Token::kText) return fail(body.line, "<" + name + "> needs a value");
        if (!tok.next(close, what)) return fail(close.line, what);
        if (close.kind != Token::kClose || close.text != name)
            return fail(close.line, "expected </" + name + ">");
        text = body.text;
        return true;
    };

    if (!tok.next(t, what)) return fail(t.line, what);
    if (t.kind != Token::kOpen || t.text != "tagDocument")
        return fail(t.line, "expected <tagDocument> (a Sznitman annotation file)");
    for (;;) {
        if (!tok.next(t, what)) return fail(t.line, what);
        if (t.kind == Token::kClose && t.text == "tagDocument") break;
        if (t.kind == Token::kEnd) return fail(t.line, "missing </tagDocument>");
        if (t.kind == Token::kOpen && t.text == "numberOfFrames") {
            std::string text;
            int line = 0;
            std::vector<double> v;
            if (!element_text(t.text, text, line)) return false;
            if (!parse_numbers(text, v) || v.size() != 1 || v[0] < 0)
                return fail(line, "<numberOfFrames> must be a count, got '" + text + "'");
            out.declared_frames = static_cast<int>(v[0]);
            continue;
        }
        if (t.kind != Token::kOpen || t.text != "frame")
            return fail(t.line, "unexpected " + std::string(t.kind == Token::kText ? "text '" + t.text + "'" : "<" + t.text + ">") + " (expected <frame>)");
        SznitmanFrame f;
        f.line = t.line;
        bool has_index = false;
        for (;;) {
            if (!tok.next(t, what)) return fail(t.line, what);
            if (t.kind == Token::kClose && t.text == "frame") break;
            if (t.kind == Token::kOpen && t.text == "frame")
                return fail(t.line, "<frame> inside <frame> (missing </frame>)");
            std::string text;
            int line = 0;
            std::vector<double> v;
            if (t.kind == Token::kOpen && t.text == "PositionIndex") {
                if (!element_text(t.text, text, line)) return false;
                if (has_index) return fail(line, "<frame> has two <PositionIndex>");
                if (!parse_numbers(text, v) || v.size() != 1 || v[0] < 0 || v[0] != static_cast<int>(v[0]))
                    return fail(line, "<PositionIndex> must be a frame number, got '" + text + "'");
                f.index = static_cast<int>(v[0]);
                has_index = true;
            } else if (t.kind == Token::kOpen && t.text == "tool") {
                if (!element_text(t.text, text, line)) return false;
                if (!parse_numbers(text, v) || v.size() != 4)
                    return fail(line, "<tool> needs 4 numbers ROW COL SCALE ANGLE, got '" + text + "'");
                if (!(v[2] > 0)) return fail(line, "<tool> SCALE must be > 0, got '" + text + "'");
                f.tools.push_back({v[0], v[1], v[2], v[3]});
            } else {
                return fail(t.line, t.kind == Token::kEnd ? std::string("missing </frame>")
                                                          : "unexpected '" + t.text + "' in <frame>");
            }
        }
        if (!has_index) return fail(f.line, "<frame> without <PositionIndex>");
        if (!seen.insert(f.index).second) {
            ++out.duplicates_dropped;  // the README: keep the first
            continue;
        }
        out.frames.push_back(std::move(f));
    }
    if (out.declared_frames >= 0 && out.declared_frames != static_cast<int>(out.frames.size()))
        return fail(1, "<numberOfFrames> says " + std::to_string(out.declared_frames) + " but " +
                           std::to_string(out.frames.size()) + " distinct frames are listed");
    return true;
}

}  // namespace endotower::eval
