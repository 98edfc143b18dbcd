/**
 * @file overlay.h
 * @brief ROS-agnostic drawing of the collision feedback on one endoscope image (D7.2 Section 7):
 *        colour classification by distance, tool shafts, out-of-view border markers and the HUD.
 */
#ifndef SARAS_VISUAL_FEEDBACK_OVERLAY_H
#define SARAS_VISUAL_FEEDBACK_OVERLAY_H

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include <opencv2/core.hpp>

#include "saras_visual_feedback/raw_projector.h"

namespace saras_visual_feedback
{

/// A colour in RGB order (0..255), independent of the image's channel order.
struct Rgb
{
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

/// Parses "#RRGGBB" (or "RRGGBB"), case-insensitive hexadecimal; false on any other text.
bool parseColour(const std::string& text, Rgb* colour);

/// Channel order of the image being drawn on.
enum class ChannelOrder
{
  kBgr,  ///< bgr8 / bgra8
  kRgb   ///< rgb8 / rgba8
};

/// Proximity region of a tool, from the distance reported by the collision node.
enum class Proximity
{
  kUnknown,    ///< no (valid, fresh) distance: drawn in the "unknown" colour
  kSafe,       ///< distance >= warning_threshold: green
  kWarning,    ///< collision_threshold < distance < warning_threshold: yellow
  kCollision   ///< distance <= collision_threshold: red
};

/// Drawing parameters; set from config/visual_feedback.yaml and dynamic_reconfigure.
struct OverlayStyle
{
  double collision_threshold = 0.005;  ///< [m] red at or below (saras_collision's default)
  double warning_threshold = 0.02;     ///< [m] yellow below, green at or above
  Rgb collision_colour{255, 0, 0};     ///< RGB
  Rgb warning_colour{255, 255, 0};     ///< RGB
  Rgb safe_colour{0, 255, 0};          ///< RGB
  Rgb unknown_colour{160, 160, 160};   ///< RGB, distance missing, stale or NaN
  int line_thickness = 3;              ///< shaft line width [px]
  int circle_radius = 6;               ///< radius of the tip/shaft circles [px]
  int marker_size = 18;                ///< size of the out-of-view border marker [px]
  int shaft_segments = 8;              ///< polyline segments of the (distorted) shaft, >= 1
  bool draw_hud = true;                ///< distances in mm at the top-left corner
};

/// Checks ranges and ordering; on failure names the offending parameter in @p error.
bool validateStyle(const OverlayStyle& style, std::string* error);

/// Region of @p distance [m]: NaN -> unknown, <= collision -> collision, < warning -> warning.
Proximity classify(double distance, const OverlayStyle& style);

/// The colour of a region.
Rgb colourOf(Proximity p, const OverlayStyle& style);

/// One tool to draw, with its points already expressed in the camera optical frame.
struct ToolOverlay
{
  const char* label = "";  ///< HUD label (not copied; must outlive the draw call)
  bool visible = false;    ///< false: no fresh pose/transform; only the HUD line is drawn
  cv::Point3d tip;         ///< tool tip [m], camera optical frame
  bool has_shaft = false;  ///< false: only the tip is drawn
  cv::Point3d shaft;       ///< point on the shaft towards the trocar [m], camera optical frame
  double distance = std::numeric_limits<double>::quiet_NaN();  ///< [m], NaN when unknown
};

/// How a tool ended up on the image.
enum class ToolDrawn
{
  kNothing,       ///< not visible (no pose/transform)
  kShaft,         ///< tip projected inside the image: line + circles
  kBorderMarker   ///< tip out of view (outside, behind or beyond the lens's range): border marker
};

/// Per-tool result of a draw call (for tests and statistics).
struct ToolDrawResult
{
  ToolDrawn drawn = ToolDrawn::kNothing;
  Proximity proximity = Proximity::kUnknown;
  cv::Point2d tip_pixel;     ///< projected tip [px] (kShaft)
  cv::Point2d marker_pixel;  ///< marker centre [px] (kBorderMarker)
};

/// Largest OverlayStyle::shaft_segments.
constexpr int kMaxShaftSegments = 64;

/// Maximum number of tools drawn per image (2 SARAS tools + 2 da Vinci tools).
constexpr std::size_t kMaxTools = 4;

/**
 * @brief Renders and caches the HUD text block. One per image stream; not thread-safe.
 *
 * Rasterising anti-aliased Hershey text (cv::putText) is expensive: ~1 ms a line at 1080p
 * (every stroke is a thick anti-aliased polyline with round caps), i.e. ~5 ms for the HUD,
 * and the distances change its text at their 20 Hz rate. Two levels of caching:
 *  - the text block (colours applied, plus its outline mask) is re-composed only when its
 *    content, colours or the image format change, and blitted through the mask otherwise;
 *  - re-composition does not call cv::putText per line: each character is rasterised once
 *    (per font scale) into a glyph atlas, with exactly the strokes cv::putText draws for it, and
 *    lines are laid out with cv::putText's advances (the Hershey widths); a glyph lands on
 *    the pixel grid at most 0.5 px from where cv::putText would put it (the test checks the
 *    result against cv::putText).
 */
class HudCache
{
public:
  /// Draws @p n lines (text, RGB colour) at the top-left corner of @p image.
  void draw(cv::Mat& image, ChannelOrder order, const char* const* lines, const Rgb* colours, std::size_t n);

  /// Number of text-block (re-)compositions since construction.
  std::size_t renders() const { return renders_; }

  /// Number of glyphs rasterised with cv::putText since construction (atlas misses).
  std::size_t glyphRenders() const { return glyph_renders_; }

  /**
   * @brief Draws one line of text like cv::putText(image, text, origin, FONT_HERSHEY_SIMPLEX,
   *        scale, colour, thickness, LINE_AA) would on a black image, from the glyph atlas;
   *        @p mask (CV_8UC1, same size, optional) gets the binary footprint of the same text
   *        drawn @p outline px thick. Pixels already set are kept where brighter (max).
   */
  void drawLine(cv::Mat& image, cv::Mat* mask, const char* text, cv::Point origin, double scale, int thickness,
                int outline, const cv::Scalar& colour);

private:
  /// A character rasterised at one font scale: anti-aliased fill and binary outline footprint.
  struct Glyph
  {
    bool ready = false;
    cv::Mat fill;     ///< CV_8UC1 coverage 0..255 of the glyph drawn `thickness` px thick
    cv::Mat outline;  ///< CV_8UC1 0/255, the glyph drawn `outline` px thick
    cv::Point origin; ///< cv::putText origin inside the cell [px]
    double advance = 0.0;  ///< horizontal advance [px]
  };
  const Glyph& glyph(unsigned char c);

  std::string key_;
  cv::Mat block_, mask_;
  std::size_t renders_ = 0;
  // Glyph atlas for printable ASCII (others are drawn as '?', as cv::putText does).
  static constexpr int kFirstGlyph = 32, kGlyphCount = 95;
  Glyph glyphs_[kGlyphCount];
  double glyph_scale_ = 0.0;
  int glyph_thickness_ = 0, glyph_outline_ = 0;
  std::size_t glyph_renders_ = 0;
};

/**
 * @brief Draws tools on an 8-bit, 3- or 4-channel image in place.
 *
 * @param image    CV_8UC3 or CV_8UC4 (other types: nothing drawn, returns false)
 * @param order    channel order of @p image
 * @param camera   a valid model of the camera that took @p image (same size)
 * @param tools    @p n tools, n <= kMaxTools (extra ones are ignored)
 * @param results  optional, @p n entries filled
 * @param status_line optional text drawn under the HUD (e.g. a warning), nullptr for none
 * @param hud      optional cache of the HUD text (nullptr: rendered directly)
 */
bool drawOverlay(cv::Mat& image, ChannelOrder order, const RawProjector& camera, const OverlayStyle& style,
                 const ToolOverlay* tools, std::size_t n, ToolDrawResult* results,
                 const char* status_line = nullptr, HudCache* hud = nullptr);

/**
 * @brief Where the out-of-view marker goes: the point where the ray from the principal point
 *        (clamped into the image) along @p direction leaves the image shrunk by @p inset pixels.
 */
cv::Point2d borderPoint(const cv::Point2d& direction, const CameraIntrinsics& k, double inset);

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_OVERLAY_H
