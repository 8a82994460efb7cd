// Shared by the book's region and edge trackers (ekf, mog2, particle, hybrid, mhi):
// the reduced analysis image with its lit field of view, and the two ways a tool
// estimate is made from what a tracker found, in full-resolution coordinates:
//  - describe_pair: from the tool's two edges (analysis pixels): the tip along the
//    midline (TipExtractor, fig. 4.19-4.21), the head where the edges end;
//  - describe_region: from a binary tool region: the axis by second moments, the
//    incision at the end nearer the field of view's rim, the tip at the far end
//    (mean of the region's last `tip_fraction` of its length), width = area/length,
//    head `head_widths` widths back from the tip, the edges +-width/2 of the axis.
// Private to app/vision: OpenCV types; buffers are sized in configure(), nothing
// is allocated per frame.
#pragma once

#include <limits>
#include <opencv2/core.hpp>
#include <vector>

#include "endotower/vision/area_mean.hpp"
#include "endotower/vision/tip_extractor.hpp"
#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision::detail {

struct AnalysisFrame {
    double scale = 1.0;  // analysis pixels per full-resolution pixel
    cv::Mat small, gray, lit, kernel;
    AreaMean reduce;  // INTER_AREA without cv::resize's per-call allocation
    FieldOfView fov;
    int surround_level = 20;

    void configure(const hal::FrameFormat& format, int analysis_width, int surround_margin_px);
    // Reduces a BGR24 frame; false when it is not BGR24 or configure() was not called.
    bool load(const hal::Frame& frame);
    hal::Frame small_frame() const;
    // Distance of p (analysis pixels) inside the field of view's rim.
    double rim_distance(Point2 p) const;
};

void describe_pair(const AnalysisFrame& a, const EdgePair& pair, int id, double jaw_length_widths,
                   const TipExtractorParams& tip_params, ToolEstimate& out);

struct RegionShapeParams {
    double min_area_fraction = 0.002;  // of the analysis image
    double min_elongation = 2.0;       // length / width
    double tip_fraction = 0.03;
    double head_widths = 2.7;  // the likelihood tracker's measured tip-to-head distance
    // When both ends are about as far from the rim (within a width), the tip is the
    // end towards this image direction (degrees, e.g. the motion's), if finite.
    double tip_direction_deg = std::numeric_limits<double>::quiet_NaN();
    bool largest_component = false;  // only the mask's largest 8-connected component
};

class RegionDescriber {
public:
    void configure(int width, int height);
    // `mask` (CV_8UC1, analysis size) non-zero on the tool, only inside `roi`.
    bool describe(const AnalysisFrame& a, const cv::Mat& mask, cv::Rect roi,
                  const RegionShapeParams& params, int id, ToolEstimate& out);

private:
    std::vector<int> histogram_;
    cv::Mat labels_, stats_, centroids_, component_;
};

// Angle between two axis directions as lines, degrees in [0, 90].
double line_angle_deg(double a_deg, double b_deg);

}  // namespace endotower::vision::detail
