#include "scene_batch.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace endotower::gles {

namespace {

constexpr float kPi = 3.14159265358979f;

struct Bounds {
    float x0 = 1e30f, y0 = 1e30f, x1 = -1e30f, y1 = -1e30f;
    void add(float x, float y) {
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
    }
    bool valid() const { return x1 > x0 && y1 > y0; }
};

void set_colour(float* out, const hal::Rgba8& c) {
    out[0] = c.r / 255.f, out[1] = c.g / 255.f, out[2] = c.b / 255.f, out[3] = c.a / 255.f;
}

long long area(const hal::Rect& r) {
    return static_cast<long long>(r.width) * r.height;
}

hal::Rect unite(const hal::Rect& a, const hal::Rect& b) {
    const int x0 = std::min(a.x, b.x), y0 = std::min(a.y, b.y);
    const int x1 = std::max(a.x + a.width, b.x + b.width);
    const int y1 = std::max(a.y + a.height, b.y + b.height);
    return {x0, y0, x1 - x0, y1 - y0};
}

bool overlap(const hal::Rect& a, const hal::Rect& b) {
    return a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height &&
           b.y < a.y + a.height;
}

class Builder {
public:
    Builder(SceneBatch& b, int w, int h) : b_(b), w_(w), h_(h) {}
    DrawList list = kQuads;

    std::size_t used() const {
        switch (list) {
            case kTexts:
                return b_.text_used;
            case kImages:
                return b_.images_used;
            case kBoxes:
                return b_.boxes_used;
            default:
                return b_.shapes_used;
        }
    }
    // Ends the item opened by the last successful cover().
    void close() {
        b_.items[b_.items_used - 1].count =
            static_cast<std::uint32_t>(used() - b_.items[b_.items_used - 1].first);
    }

    // Grows the bounds by one pixel for the antialiased edge, snaps them to whole
    // pixels and records the rect; false when nothing of it is on screen.
    bool cover(Bounds& bounds) {
        if (!bounds.valid()) return false;
        bounds.x0 = std::floor(bounds.x0 - 1.f), bounds.y0 = std::floor(bounds.y0 - 1.f);
        bounds.x1 = std::ceil(bounds.x1 + 1.f), bounds.y1 = std::ceil(bounds.y1 + 1.f);
        const int x0 = std::max(0, static_cast<int>(std::max(bounds.x0, -1.f)));
        const int y0 = std::max(0, static_cast<int>(std::max(bounds.y0, -1.f)));
        const int x1 = std::min(w_, static_cast<int>(std::min(bounds.x1, w_ + 1.f)));
        const int y1 = std::min(h_, static_cast<int>(std::min(bounds.y1, h_ + 1.f)));
        if (x1 <= x0 || y1 <= y0 || b_.items_used == b_.items.size()) return false;
        b_.rects.add({x0, y0, x1 - x0, y1 - y0});
        BatchItem& item = b_.items[b_.items_used++];
        item.list = list;
        item.first = static_cast<std::uint32_t>(used());
        item.count = 0;
        item.rect = {x0, y0, x1 - x0, y1 - y0};
        // Geometry past the frame is clipped by GL; keep it near so floats stay exact.
        bounds.x0 = static_cast<float>(x0), bounds.y0 = static_cast<float>(y0);
        bounds.x1 = static_cast<float>(x1), bounds.y1 = static_cast<float>(y1);
        return true;
    }

    void shape(Bounds bounds, float ox, float oy, const float (&s)[4], const float (&s2)[4],
               const hal::Rgba8& fill, const hal::Rgba8& border) {
        if (b_.shapes_used + 6 > b_.shapes.size() || !cover(bounds)) return;
        const float xs[6] = {bounds.x0, bounds.x1, bounds.x0, bounds.x0, bounds.x1, bounds.x1};
        const float ys[6] = {bounds.y0, bounds.y0, bounds.y1, bounds.y1, bounds.y0, bounds.y1};
        for (int k = 0; k < 6; ++k) {
            ShapeVertex& v = b_.shapes[b_.shapes_used++];
            v.x = xs[k], v.y = ys[k], v.lx = xs[k] - ox, v.ly = ys[k] - oy;
            std::copy(s, s + 4, v.shape);
            std::copy(s2, s2 + 4, v.shape2);
            set_colour(v.fill, fill);
            set_colour(v.border, border);
        }
        close();
    }

    void segment(hal::Vec2f a, hal::Vec2f c, float width, const hal::Rgba8& colour) {
        const float half = std::max(width, 0.f) / 2.f;
        Bounds bounds;
        bounds.add(a.x - half, a.y - half);
        bounds.add(c.x + half, c.y + half);
        bounds.add(a.x + half, a.y + half);
        bounds.add(c.x - half, c.y - half);
        const float s[4] = {c.x - a.x, c.y - a.y, half, 0};
        const float s2[4] = {0, 0, 0, 0};
        shape(bounds, a.x, a.y, s, s2, colour, colour);
    }

    // An annular sector from `start` clockwise to `end` (radians, end > start).
    void sector(float cx, float cy, float r_in, float r_out, float start, float end, float border,
                const hal::Rgba8& fill, const hal::Rgba8& border_colour) {
        if (r_out <= 0 || end <= start) return;
        const bool full = end - start >= 2 * kPi - 1e-6f;
        Bounds bounds;
        if (full) {
            bounds.add(cx - r_out, cy - r_out);
            bounds.add(cx + r_out, cy + r_out);
        } else {
            const float ri = std::max(r_in, 0.f);
            for (float a : {start, end}) {
                bounds.add(cx + ri * std::cos(a), cy + ri * std::sin(a));
                bounds.add(cx + r_out * std::cos(a), cy + r_out * std::sin(a));
            }
            // The extremes along the axes that the arc passes.
            for (float q = std::ceil(start / (kPi / 2)) * (kPi / 2); q <= end; q += kPi / 2)
                bounds.add(cx + r_out * std::cos(q), cy + r_out * std::sin(q));
        }
        // The angular limits as two half-planes through the centre (normals pointing
        // out of the sector): inside both for a span up to 180 deg, either past it.
        const float mode = full ? 0.f : (end - start <= kPi ? 1.f : 2.f);
        const float s[4] = {r_in > 0 ? r_in : -1e6f, r_out, border, mode};
        const float s2[4] = {std::sin(start), -std::cos(start), -std::sin(end), std::cos(end)};
        shape(bounds, cx, cy, s, s2, fill, border_colour);
    }

    bool project(const hal::SceneCamera& cam, const hal::Vec3f& p, hal::Vec2f& out) const {
        if (p.z < cam.near_mm) return false;
        out.x = static_cast<float>(cam.fx * p.x / p.z + cam.cx + 0.5);
        out.y = static_cast<float>(cam.fy * p.y / p.z + cam.cy + 0.5);
        return true;
    }

    // A 3-D segment cut at the near plane, then projected.
    void segment3(const hal::SceneCamera& cam, hal::Vec3f a, hal::Vec3f c, float width,
                  const hal::Rgba8& colour) {
        const float n = static_cast<float>(cam.near_mm);
        if (a.z < n && c.z < n) return;
        if (a.z < n || c.z < n) {
            hal::Vec3f& behind = a.z < n ? a : c;
            const hal::Vec3f& front = a.z < n ? c : a;
            const float t = (n - front.z) / (behind.z - front.z);
            behind = {front.x + t * (behind.x - front.x), front.y + t * (behind.y - front.y), n};
        }
        hal::Vec2f pa, pc;
        if (project(cam, a, pa) && project(cam, c, pc)) segment(pa, pc, width, colour);
    }

    void box(const hal::SceneCamera& cam, const hal::SceneBox& box) {
        if (b_.boxes_used + 36 > b_.boxes.size() || box.size_mm <= 0) return;
        const auto& m = box.camera_from_model;
        const float h = box.size_mm / 2;
        auto to_camera = [&](float x, float y, float z, float w) {
            return hal::Vec3f{m[0] * x + m[4] * y + m[8] * z + m[12] * w,
                              m[1] * x + m[5] * y + m[9] * z + m[13] * w,
                              m[2] * x + m[6] * y + m[10] * z + m[14] * w};
        };
        // The screen bounds of the 8 corners; a corner behind the near plane: all of it.
        Bounds bounds;
        bool all_front = true;
        for (int k = 0; k < 8; ++k) {
            const hal::Vec3f p = to_camera(k & 1 ? h : -h, k & 2 ? h : -h, k & 4 ? h : -h, 1);
            hal::Vec2f uv;
            if (project(cam, p, uv))
                bounds.add(uv.x, uv.y);
            else
                all_front = false;
        }
        if (!all_front) bounds = {0, 0, static_cast<float>(w_), static_cast<float>(h_)};
        if (!cover(bounds)) return;
        // Face f: normal axis f / 2, sign + for even f; two triangles of its 4 corners.
        for (int f = 0; f < 6; ++f) {
            const int axis = f / 2;
            const float sign = f % 2 == 0 ? 1.f : -1.f;
            float n[3] = {0, 0, 0};
            n[axis] = sign;
            const hal::Vec3f nc = to_camera(n[0], n[1], n[2], 0);
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            const float us[6] = {-h, h, -h, -h, h, h}, vs[6] = {-h, -h, h, h, -h, h};
            for (int k = 0; k < 6; ++k) {
                float p[3];
                p[axis] = sign * h, p[u] = us[k], p[v] = vs[k];
                const hal::Vec3f pc = to_camera(p[0], p[1], p[2], 1);
                BoxVertex& out = b_.boxes[b_.boxes_used++];
                out.x = pc.x, out.y = pc.y, out.z = pc.z;
                out.nx = nc.x, out.ny = nc.y, out.nz = nc.z;
                set_colour(out.colour, box.faces[static_cast<std::size_t>(f)]);
            }
        }
        close();
    }

    void tex_quad(std::vector<TexVertex>& out, std::size_t& used, float x0, float y0, float x1,
                  float y1, float u0, float v0, float u1, float v1, const float (&colour)[4]) {
        const float xs[6] = {x0, x1, x0, x0, x1, x1}, ys[6] = {y0, y0, y1, y1, y0, y1};
        const float us[6] = {u0, u1, u0, u0, u1, u1}, vs[6] = {v0, v0, v1, v1, v0, v1};
        for (int k = 0; k < 6; ++k) {
            TexVertex& t = out[used++];
            t.x = xs[k], t.y = ys[k], t.u = us[k], t.v = vs[k];
            std::copy(colour, colour + 4, t.colour);
        }
    }

    void text(const hal::SceneText& t, const GlyphAtlas& atlas) {
        if (t.size_px <= 0) return;
        const GlyphFace& face = atlas.pick(t.size_px);
        const float scale = t.size_px / static_cast<float>(face.line_height);
        const char* s = t.utf8.data();
        const std::size_t n = strnlen(s, t.utf8.size());
        float width = 0;
        for (std::size_t i = 0; i < n;) width += face.at(next_code_point(s, i)).advance * scale;
        float pen = t.x, top = t.y;
        if (t.align == hal::SceneText::Align::kCentre) pen -= width / 2, top -= t.size_px / 2;
        pen = std::round(pen);
        const float baseline = std::round(top + static_cast<float>(face.ascender) * scale);
        float colour[4];
        set_colour(colour, t.colour);
        Bounds bounds;
        float x = pen;
        for (std::size_t i = 0; i < n;) {
            const Glyph& g = face.at(next_code_point(s, i));
            if (g.width > 0 && g.height > 0) {
                bounds.add(x + g.left * scale, baseline - g.top * scale);
                bounds.add(x + (g.left + g.width) * scale, baseline + (g.height - g.top) * scale);
            }
            x += g.advance * scale;
        }
        if (!cover(bounds)) return;
        for (std::size_t i = 0; i < n;) {
            const Glyph& g = face.at(next_code_point(s, i));
            if (g.width > 0 && g.height > 0 && b_.text_used + 6 <= b_.text.size()) {
                const float x0 = pen + g.left * scale, y0 = baseline - g.top * scale;
                const float x1 = x0 + g.width * scale, y1 = y0 + g.height * scale;
                tex_quad(b_.text, b_.text_used, x0, y0, x1, y1, g.u0, g.v0, g.u1, g.v1, colour);
            }
            pen += g.advance * scale;
        }
        close();
    }

    void image(const hal::SceneImage& im) {
        if (im.image_id < 0 || im.image_id >= hal::OverlayRenderer::kMaxImages ||
            !b_.image_present[static_cast<std::size_t>(im.image_id)] ||
            b_.images_used + 6 > b_.images.size())
            return;
        if (im.warped) return warped_image(im);
        Bounds bounds;
        bounds.add(im.x, im.y);
        bounds.add(im.x + im.width, im.y + im.height);
        Bounds covered = bounds;
        if (!cover(covered)) return;
        // The id rides in the colour's second channel, the projective q in the third
        // (the shader samples at uv / q; 1 for a rectangle).
        const float colour[4] = {std::clamp(im.opacity, 0.f, 1.f), static_cast<float>(im.image_id),
                                 1, 0};
        tex_quad(b_.images, b_.images_used, bounds.x0, bounds.y0, bounds.x1, bounds.y1, 0, 0, 1, 1,
                 colour);
        close();
    }

    // Projective texture coordinates: with the diagonals meeting at c, a corner at
    // distance d_i from c and its opposite at d_(i+2) get q_i = (d_i + d_(i+2)) / d_(i+2)
    // and (u q, v q, q); interpolated linearly on screen and divided per fragment, they
    // give exactly the homography that maps the image's corners onto the quad.
    void warped_image(const hal::SceneImage& im) {
        const auto& p = im.corners;
        // Convex, either orientation: every turn the same sign.
        int pos = 0, neg = 0;
        for (int k = 0; k < 4; ++k) {
            const hal::Vec2f a = p[k], b = p[(k + 1) % 4], c = p[(k + 2) % 4];
            const float turn = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
            pos += turn > 0, neg += turn < 0;
        }
        if (pos != 4 && neg != 4) return;
        // Diagonals p0 + s (p2 - p0) and p1 + t (p3 - p1).
        const float ax = p[2].x - p[0].x, ay = p[2].y - p[0].y;
        const float bx = p[3].x - p[1].x, by = p[3].y - p[1].y;
        const float den = ax * by - ay * bx;
        const float s = ((p[1].x - p[0].x) * by - (p[1].y - p[0].y) * bx) / den;
        const float t = ((p[1].x - p[0].x) * ay - (p[1].y - p[0].y) * ax) / den;
        if (!(s > 0 && s < 1 && t > 0 && t < 1)) return;
        // Distances to the crossing as fractions of each diagonal (the ratios are what count).
        const float d[4] = {s, t, 1 - s, 1 - t};
        Bounds bounds;
        for (const hal::Vec2f& c : p) bounds.add(c.x, c.y);
        if (!cover(bounds)) return;
        constexpr float kU[4] = {0, 1, 1, 0}, kV[4] = {0, 0, 1, 1};
        constexpr int kOrder[6] = {0, 1, 2, 0, 2, 3};
        for (int k : kOrder) {
            const float q = (d[k] + d[(k + 2) % 4]) / d[(k + 2) % 4];
            TexVertex& v = b_.images[b_.images_used++];
            v.x = p[k].x, v.y = p[k].y, v.u = kU[k] * q, v.v = kV[k] * q;
            v.colour[0] = std::clamp(im.opacity, 0.f, 1.f);
            v.colour[1] = static_cast<float>(im.image_id);
            v.colour[2] = q, v.colour[3] = 0;
        }
        close();
    }

private:
    SceneBatch& b_;
    int w_, h_;
};

}  // namespace

void RectSet::merge_into(std::size_t keep, std::size_t drop) {
    rects_[keep] = unite(rects_[keep], rects_[drop]);
    rects_[drop] = rects_[--count_];
}

void RectSet::add(const hal::Rect& r) {
    if (r.empty()) return;
    hal::Rect grown = r;
    // Absorb every rect it overlaps, again after each growth.
    for (bool merged = true; merged;) {
        merged = false;
        for (std::size_t i = 0; i < count_; ++i)
            if (overlap(grown, rects_[i])) {
                grown = unite(grown, rects_[i]);
                rects_[i] = rects_[--count_];
                merged = true;
                break;
            }
    }
    if (count_ == kCapacity) {
        // Full: fold the new rect into its cheapest neighbour instead.
        std::size_t best = 0;
        long long best_growth = -1;
        for (std::size_t i = 0; i < count_; ++i) {
            const long long g = area(unite(grown, rects_[i])) - area(rects_[i]);
            if (best_growth < 0 || g < best_growth) best = i, best_growth = g;
        }
        grown = unite(grown, rects_[best]);
        rects_[best] = rects_[--count_];
        add(grown);
        return;
    }
    rects_[count_++] = grown;
}

void RectSet::finish(hal::Rect* out, std::size_t& count, std::size_t max) {
    while (count_ > max) {
        std::size_t bi = 0, bj = 1;
        long long best = -1;
        for (std::size_t i = 0; i < count_; ++i)
            for (std::size_t j = i + 1; j < count_; ++j) {
                const long long g =
                    area(unite(rects_[i], rects_[j])) - area(rects_[i]) - area(rects_[j]);
                if (best < 0 || g < best) bi = i, bj = j, best = g;
            }
        const hal::Rect u = unite(rects_[bi], rects_[bj]);
        rects_[bj] = rects_[--count_];
        rects_[bi] = rects_[--count_];
        add(u);
    }
    count = count_;
    std::copy(rects_.begin(), rects_.begin() + static_cast<std::ptrdiff_t>(count_), out);
}

std::array<float, 16> clip_from_camera(const hal::SceneCamera& c, int width, int height) {
    const double w = width, h = height, n = c.near_mm, f = c.far_mm;
    std::array<float, 16> m{};
    m[0] = static_cast<float>(2 * c.fx / w);
    m[5] = static_cast<float>(2 * c.fy / h);
    m[8] = static_cast<float>(2 * (c.cx + 0.5) / w - 1);
    m[9] = static_cast<float>(2 * (c.cy + 0.5) / h - 1);
    m[10] = static_cast<float>((f + n) / (f - n));
    m[11] = 1;
    m[14] = static_cast<float>(-2 * f * n / (f - n));
    return m;
}

void SceneBatch::reserve() {
    static const hal::OverlayScene kCapacities;  // only the list sizes are read
    const hal::OverlayScene* s = &kCapacities;
    const std::size_t line_segments = s->lines.items.size() * 64 + s->lines3.items.size() * 63;
    const std::size_t shape_items =
        s->quads.items.size() + s->sectors.items.size() + s->discs.items.size() + line_segments;
    shapes.resize(6 * shape_items);
    text.resize(6 * s->texts.items.size() * sizeof(hal::SceneText::utf8));
    images.resize(6 * s->images.items.size());
    boxes.resize(36 * s->boxes.items.size());
    items.resize(shape_items + s->texts.items.size() + s->images.items.size() +
                 s->boxes.items.size());
    draw_shapes.resize(shapes.size());
    draw_text.resize(text.size());
    draw_images.resize(images.size());
    draw_boxes.resize(boxes.size());
}

namespace {

// FNV-1a over 32-bit words: cheap, and enough to tell a changed item from an unchanged one.
std::uint64_t hash_words(std::uint64_t h, const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i + 4 <= bytes; i += 4) {
        std::uint32_t w;
        std::memcpy(&w, p + i, 4);
        h = (h ^ w) * 1099511628211ull;
    }
    return h;
}

}  // namespace

void SceneBatch::build(const hal::OverlayScene& scene, const GlyphAtlas& atlas, int width,
                       int height) {
    shapes_used = text_used = images_used = boxes_used = items_used = 0;
    rects.clear();
    Builder b(*this, width, height);
    const hal::SceneCamera& cam = scene.camera;
    const bool camera_ok = cam.valid() && cam.far_mm > cam.near_mm && cam.near_mm > 0;
    if (camera_ok) {
        b.list = kBoxes;
        for (const hal::SceneBox& box : scene.boxes) b.box(cam, box);
        b.list = kLines3;
        for (const hal::SceneLine3& l : scene.lines3)
            for (std::size_t i = 1; i < std::min<std::size_t>(l.count, l.points.size()); ++i)
                b.segment3(cam, l.points[i - 1], l.points[i], l.width_px, l.colour);
    }
    b.list = kImages;
    for (const hal::SceneImage& im : scene.images) b.image(im);
    constexpr float kDeg = kPi / 180.f;
    b.list = kSectors;
    for (const hal::SceneSector& s : scene.sectors) {
        float end = s.end_deg;
        while (end <= s.start_deg) end += 360.f;  // "from start clockwise to end"
        b.sector(s.cx, s.cy, s.r_inner, s.r_outer, s.start_deg * kDeg,
                 std::min(end, s.start_deg + 360.f) * kDeg, s.border_px, s.fill, s.border);
    }
    b.list = kQuads;
    for (const hal::SceneQuad& q : scene.quads) {
        if (q.width <= 0 || q.height <= 0) continue;
        Bounds bounds;
        bounds.add(q.x, q.y);
        bounds.add(q.x + q.width, q.y + q.height);
        const float s[4] = {q.width / 2, q.height / 2,
                            std::clamp(q.corner_px, 0.f, std::min(q.width, q.height) / 2),
                            q.border_px};
        const float s2[4] = {0, 0, 0, 0};
        b.shape(bounds, q.x + q.width / 2, q.y + q.height / 2, s, s2, q.fill, q.border);
    }
    b.list = kLines;
    for (const hal::SceneLine& l : scene.lines) {
        const std::size_t n = std::min<std::size_t>(l.count, l.points.size());
        for (std::size_t i = 1; i < n; ++i)
            b.segment(l.points[i - 1], l.points[i], l.width_px, l.colour);
        if (l.closed && n >= 3) b.segment(l.points[n - 1], l.points[0], l.width_px, l.colour);
    }
    b.list = kDiscs;
    for (const hal::SceneDisc& d : scene.discs) {
        const float sweep = std::min(d.sweep_deg, 360.f);
        if (sweep <= 0) continue;
        b.sector(d.cx, d.cy, d.r_inner, d.r_outer, -kPi / 2, -kPi / 2 + sweep * kDeg, 0, d.colour,
                 d.colour);
    }
    b.list = kTexts;
    for (const hal::SceneText& t : scene.texts) b.text(t, atlas);
    rects.finish(regions.data(), region_count, kMaxRegions);
    rects.finish(drawn.rects.data(), drawn.count, drawn.rects.size());

    // What each rect shows: its geometry and its items' vertices in draw order (the
    // camera for boxes, the image's version for images).
    for (std::size_t i = 0; i < region_count; ++i)
        region_hash[i] = hash_words(14695981039346656037ull, &regions[i], sizeof(hal::Rect));
    const std::array<float, 16> clip = clip_from_camera(cam, width, height);
    for (std::size_t k = 0; k < items_used; ++k) {
        BatchItem& item = items[k];
        const hal::Rect& r = item.rect;
        for (std::size_t i = 0; i < region_count; ++i) {
            const hal::Rect& d = regions[i];
            if (r.x >= d.x && r.y >= d.y && r.x + r.width <= d.x + d.width &&
                r.y + r.height <= d.y + d.height) {
                item.region = i;
                break;
            }
        }
        std::uint64_t& h = region_hash[item.region];
        h = hash_words(h, &item.list, 1) ^ item.list;
        switch (item.list) {
            case kTexts:
                h = hash_words(h, &text[item.first], item.count * sizeof(TexVertex));
                break;
            case kImages: {
                const auto id = static_cast<std::size_t>(images[item.first].colour[1]);
                h = hash_words(h, &images[item.first], item.count * sizeof(TexVertex));
                h = hash_words(h, &image_version[id], sizeof(std::uint64_t));
                break;
            }
            case kBoxes:
                h = hash_words(h, &boxes[item.first], item.count * sizeof(BoxVertex));
                h = hash_words(h, clip.data(), sizeof clip);
                break;
            default:
                h = hash_words(h, &shapes[item.first], item.count * sizeof(ShapeVertex));
        }
    }
}

void SceneBatch::select(const std::array<bool, kMaxRegions>& redraw) {
    std::array<std::size_t, kListCount> shape_count{};
    std::size_t n_shapes = 0;
    draw_text_used = draw_images_used = draw_boxes_used = 0;
    for (std::size_t k = 0; k < items_used; ++k) {
        const BatchItem& item = items[k];
        if (!redraw[item.region]) continue;
        switch (item.list) {
            case kTexts:
                std::copy_n(&text[item.first], item.count, &draw_text[draw_text_used]);
                draw_text_used += item.count;
                break;
            case kImages:
                draw_image_ids[draw_images_used / 6] =
                    static_cast<int>(images[item.first].colour[1]);
                std::copy_n(&images[item.first], item.count, &draw_images[draw_images_used]);
                draw_images_used += item.count;
                break;
            case kBoxes:
                std::copy_n(&boxes[item.first], item.count, &draw_boxes[draw_boxes_used]);
                draw_boxes_used += item.count;
                break;
            default:  // shapes come list by list, in DrawList order
                std::copy_n(&shapes[item.first], item.count, &draw_shapes[n_shapes]);
                n_shapes += item.count;
                shape_count[item.list] += item.count;
        }
    }
    shape_range[0] = 0;
    for (std::size_t l = 0; l < kListCount; ++l)
        shape_range[l + 1] = shape_range[l] + shape_count[l];
}

}  // namespace endotower::gles
