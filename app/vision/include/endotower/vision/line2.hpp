// Image lines for the edge-based trackers: segments, the point-line distance of
// eq. 4.12, and slope-intercept lines that switch axes near the vertical so a
// vertical tool has no slope singularity.
#pragma once

#include "endotower/vision/tool_pose.hpp"

namespace endotower::vision {

struct Segment {
    Point2 a, b;
    double length() const;
};

// Distance from p to the infinite line through s (eq. 4.12).
double distance_to_line(Point2 p, const Segment& s);
// Largest distance of s's end points to the line through `to` (book fig. 4.9).
double max_end_distance(const Segment& s, const Segment& to);
// Smallest angle between the two lines' directions, degrees in [0, 90].
double angle_between_deg(const Segment& s, const Segment& t);

// A line as y = m x + b (x_major) or x = m y + b (!x_major): the parameterisation of
// the book's midline filter, with the axes swapped for lines steeper than 45 degrees.
struct SlopeLine {
    double m = 0, b = 0;
    bool x_major = true;

    static SlopeLine through(const Segment& s);       // picks the axis by the direction
    static SlopeLine through(const Segment& s, bool x_major);
    // The same line in the other parameterisation (m must not be 0 there).
    SlopeLine swapped() const;
    // The point of the line at parameter t (x when x_major, else y).
    Point2 at(double t) const;
    double distance(Point2 p) const;
};

}  // namespace endotower::vision
