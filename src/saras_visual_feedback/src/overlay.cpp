#include "saras_visual_feedback/overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

namespace saras_visual_feedback
{
namespace
{
cv::Scalar toScalar(const Rgb& c, ChannelOrder order)
{
  return order == ChannelOrder::kBgr ? cv::Scalar(c.b, c.g, c.r, 255) : cv::Scalar(c.r, c.g, c.b, 255);
}

int hexValue(char c)
{
  if (c >= '0' && c <= '9')
    return c - '0';
  if (c >= 'a' && c <= 'f')
    return c - 'a' + 10;
  if (c >= 'A' && c <= 'F')
    return c - 'A' + 10;
  return -1;
}

cv::Point toFixedPoint(const cv::Point2d& p, int shift)
{
  const double s = static_cast<double>(1 << shift);
  return cv::Point(static_cast<int>(std::lround(p.x * s)), static_cast<int>(std::lround(p.y * s)));
}

/// Pixel coordinates far outside the image are clamped so that the int conversion cannot overflow.
cv::Point2d clampForDrawing(const cv::Point2d& p, const CameraIntrinsics& k)
{
  const double margin = 4.0 * std::max(k.width, k.height);
  return {std::min(std::max(p.x, -margin), k.width + margin), std::min(std::max(p.y, -margin), k.height + margin)};
}

constexpr int kShift = 4;  // sub-pixel bits for cv::line / cv::circle
}  // namespace

bool parseColour(const std::string& text, Rgb* colour)
{
  std::size_t start = (!text.empty() && text[0] == '#') ? 1 : 0;
  if (text.size() != start + 6)
    return false;
  int v[6];
  for (int i = 0; i < 6; ++i)
  {
    v[i] = hexValue(text[start + i]);
    if (v[i] < 0)
      return false;
  }
  colour->r = static_cast<std::uint8_t>(v[0] * 16 + v[1]);
  colour->g = static_cast<std::uint8_t>(v[2] * 16 + v[3]);
  colour->b = static_cast<std::uint8_t>(v[4] * 16 + v[5]);
  return true;
}

bool validateStyle(const OverlayStyle& s, std::string* error)
{
  auto fail = [error](const std::string& why) {
    if (error)
      *error = why;
    return false;
  };
  if (!(std::isfinite(s.collision_threshold) && s.collision_threshold >= 0.0))
    return fail("collision_threshold must be finite and >= 0 [m]");
  if (!(std::isfinite(s.warning_threshold) && s.warning_threshold > s.collision_threshold))
    return fail("warning_threshold must be finite and > collision_threshold [m]");
  if (s.line_thickness < 1 || s.line_thickness > 50)
    return fail("line_thickness must be in [1, 50] px");
  if (s.circle_radius < 1 || s.circle_radius > 100)
    return fail("circle_radius must be in [1, 100] px");
  if (s.marker_size < 4 || s.marker_size > 200)
    return fail("marker_size must be in [4, 200] px");
  if (s.shaft_segments < 1 || s.shaft_segments > kMaxShaftSegments)
    return fail("shaft_segments must be in [1, " + std::to_string(kMaxShaftSegments) + "]");
  return true;
}

Proximity classify(double distance, const OverlayStyle& style)
{
  if (std::isnan(distance))
    return Proximity::kUnknown;
  if (distance <= style.collision_threshold)
    return Proximity::kCollision;
  if (distance < style.warning_threshold)
    return Proximity::kWarning;
  return Proximity::kSafe;
}

Rgb colourOf(Proximity p, const OverlayStyle& style)
{
  switch (p)
  {
    case Proximity::kCollision:
      return style.collision_colour;
    case Proximity::kWarning:
      return style.warning_colour;
    case Proximity::kSafe:
      return style.safe_colour;
    case Proximity::kUnknown:
    default:
      return style.unknown_colour;
  }
}

const HudCache::Glyph& HudCache::glyph(unsigned char c)
{
  if (c < kFirstGlyph || c >= kFirstGlyph + kGlyphCount)
    c = '?';  // as cv::putText
  Glyph& g = glyphs_[c - kFirstGlyph];
  if (g.ready)
    return g;
  const char text[2] = {static_cast<char>(c), '\0'};
  int base = 0;
  // Advance in font units: with scale 1 and thickness 0, getTextSize's width is the Hershey
  // width (right - left bearing) of the glyph, an integer; cv::putText moves by it times its
  // 16.16 fixed-point scale.
  const int units = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 1.0, 0, &base).width;
  const double fixed_scale = std::round(glyph_scale_ * 65536.0) / 65536.0;
  g.advance = units * fixed_scale;
  // Cell: the glyph's box with generous margins (strokes can pass the bearings and the cap
  // line, and the outline adds its half thickness).
  const cv::Size box = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, glyph_scale_, glyph_outline_, &base);
  const int margin = glyph_outline_ + 2 + static_cast<int>(std::ceil(8.0 * glyph_scale_));
  g.origin = cv::Point(margin, margin + box.height);
  const cv::Size cell(static_cast<int>(std::ceil(g.advance)) + 2 * margin, box.height + base + 2 * margin);
  g.fill = cv::Mat::zeros(cell, CV_8UC1);
  g.outline = cv::Mat::zeros(cell, CV_8UC1);
  cv::putText(g.fill, text, g.origin, cv::FONT_HERSHEY_SIMPLEX, glyph_scale_, cv::Scalar(255), glyph_thickness_,
              cv::LINE_AA);
  cv::putText(g.outline, text, g.origin, cv::FONT_HERSHEY_SIMPLEX, glyph_scale_, cv::Scalar(255), glyph_outline_,
              cv::LINE_AA);
  cv::threshold(g.outline, g.outline, 0, 255, cv::THRESH_BINARY);
  // Keep only the outline's bounding box (it contains the thinner fill): fewer pixels to blend.
  const cv::Rect ink = cv::boundingRect(g.outline);
  if (ink.area() > 0)
  {
    g.fill = g.fill(ink).clone();
    g.outline = g.outline(ink).clone();
    g.origin -= ink.tl();
  }
  else
  {
    g.fill.release();  // a space: nothing to draw
    g.outline.release();
  }
  g.ready = true;
  ++glyph_renders_;
  return g;
}

void HudCache::drawLine(cv::Mat& image, cv::Mat* mask, const char* text, cv::Point origin, double scale,
                        int thickness, int outline, const cv::Scalar& colour)
{
  CV_Assert(image.depth() == CV_8U && image.channels() <= 4);
  CV_Assert(!mask || (mask->type() == CV_8UC1 && mask->size() == image.size()));
  if (scale != glyph_scale_ || thickness != glyph_thickness_ || outline != glyph_outline_)
  {
    for (Glyph& g : glyphs_)
      g.ready = false;
    glyph_scale_ = scale;
    glyph_thickness_ = thickness;
    glyph_outline_ = outline;
  }
  const int channels = image.channels();
  int value[4];
  for (int c = 0; c < 4; ++c)
    value[c] = static_cast<int>(std::lround(std::min(255.0, std::max(0.0, colour[c]))));
  double x = origin.x;  // exact pen position [px], as cv::putText's fixed-point one
  for (const char* p = text; *p != '\0'; ++p)
  {
    const Glyph& g = glyph(static_cast<unsigned char>(*p));
    // Cell position in the image, clipped to it.
    const int x0 = static_cast<int>(std::lround(x)) - g.origin.x, y0 = origin.y - g.origin.y;
    x += g.advance;
    const cv::Rect cell = cv::Rect(x0, y0, g.fill.cols, g.fill.rows) & cv::Rect(0, 0, image.cols, image.rows);
    for (int r = cell.y; r < cell.y + cell.height; ++r)
    {
      const std::uint8_t* a = g.fill.ptr<std::uint8_t>(r - y0);
      const std::uint8_t* o = g.outline.ptr<std::uint8_t>(r - y0);
      std::uint8_t* dst = image.ptr<std::uint8_t>(r);
      std::uint8_t* m = mask ? mask->ptr<std::uint8_t>(r) : nullptr;
      for (int col = cell.x; col < cell.x + cell.width; ++col)
      {
        const int alpha = a[col - x0];
        if (m && o[col - x0])
          m[col] = 255;
        if (alpha == 0)
          continue;
        std::uint8_t* px = dst + col * channels;
        for (int c = 0; c < channels; ++c)
        {
          const int v = (value[c] * alpha + 127) / 255;  // colour over black with the coverage
          if (v > px[c])
            px[c] = static_cast<std::uint8_t>(v);
        }
      }
    }
  }
}

void HudCache::draw(cv::Mat& image, ChannelOrder order, const char* const* lines, const Rgb* colours, std::size_t n)
{
  // Key: image format + every line and colour.
  char key[1024];
  int len = std::snprintf(key, sizeof(key), "%dx%d/%d/%d|", image.cols, image.rows, image.type(), static_cast<int>(order));
  for (std::size_t i = 0; i < n && len > 0 && len < static_cast<int>(sizeof(key)); ++i)
    len += std::snprintf(key + len, sizeof(key) - len, "%s#%02x%02x%02x|", lines[i], colours[i].r, colours[i].g,
                         colours[i].b);
  const double scale = std::max(0.4, 0.6 * image.rows / 720.0);
  const int thickness = std::max(1, static_cast<int>(std::lround(scale * 1.5)));
  const int line_h = static_cast<int>(std::lround(28 * scale));
  if (key_ != key)
  {
    int width = 1;
    for (std::size_t i = 0; i < n; ++i)
    {
      int base = 0;
      width = std::max(width, cv::getTextSize(lines[i], cv::FONT_HERSHEY_SIMPLEX, scale, thickness + 2, &base).width);
    }
    const int rows = std::min(image.rows, static_cast<int>(line_h * (n + 0.5)));
    const int cols = std::min(image.cols, width + 20);
    block_.create(rows, cols, image.type());
    block_.setTo(cv::Scalar::all(0));
    mask_.create(rows, cols, CV_8UC1);
    mask_.setTo(cv::Scalar(0));
    // Text in its colour over a black outline (thickness + 2 px): the block is black wherever
    // the mask is set and the text is not.
    int y = line_h;
    for (std::size_t i = 0; i < n; ++i, y += line_h)
      drawLine(block_, &mask_, lines[i], cv::Point(10, y), scale, thickness, thickness + 2, toScalar(colours[i], order));
    key_ = key;
    ++renders_;
  }
  block_.copyTo(image(cv::Rect(0, 0, block_.cols, block_.rows)), mask_);
}

cv::Point2d borderPoint(const cv::Point2d& direction, const CameraIntrinsics& k, double inset)
{
  const double xmin = inset, ymin = inset;
  const double xmax = std::max(xmin, k.width - 1.0 - inset), ymax = std::max(ymin, k.height - 1.0 - inset);
  const cv::Point2d o(std::min(std::max(k.cx, xmin), xmax), std::min(std::max(k.cy, ymin), ymax));
  cv::Point2d d = direction;
  const double n = std::hypot(d.x, d.y);
  if (!(n > 1e-12) || !std::isfinite(n))
    d = cv::Point2d(0.0, 1.0);  // no direction: bottom edge
  else
    d *= 1.0 / n;
  double t = std::numeric_limits<double>::infinity();
  if (d.x > 1e-12)
    t = std::min(t, (xmax - o.x) / d.x);
  if (d.x < -1e-12)
    t = std::min(t, (xmin - o.x) / d.x);
  if (d.y > 1e-12)
    t = std::min(t, (ymax - o.y) / d.y);
  if (d.y < -1e-12)
    t = std::min(t, (ymin - o.y) / d.y);
  if (!std::isfinite(t))
    t = 0.0;
  return {std::min(std::max(o.x + t * d.x, xmin), xmax), std::min(std::max(o.y + t * d.y, ymin), ymax)};
}

namespace
{
/// HUD: one line per tool (distance in mm, in its region's colour) and the status line.
void drawHud(cv::Mat& image, ChannelOrder order, const OverlayStyle& style, const ToolOverlay* tools, std::size_t n,
             const char* status_line, HudCache* hud)
{
  char text[kMaxTools + 1][96];
  const char* lines[kMaxTools + 1];
  Rgb colours[kMaxTools + 1];
  std::size_t m = 0;
  if (style.draw_hud)
  {
    for (std::size_t i = 0; i < n; ++i, ++m)
    {
      const ToolOverlay& tool = tools[i];
      if (!tool.visible)
        std::snprintf(text[m], sizeof(text[m]), "%s: no pose", tool.label);
      else if (std::isnan(tool.distance))
        std::snprintf(text[m], sizeof(text[m]), "%s: -- mm", tool.label);
      else
        std::snprintf(text[m], sizeof(text[m]), "%s: %.1f mm", tool.label, tool.distance * 1e3);
      lines[m] = text[m];
      colours[m] = colourOf(classify(tool.distance, style), style);
    }
  }
  if (status_line && status_line[0] != '\0')
  {
    lines[m] = status_line;
    colours[m] = style.unknown_colour;
    ++m;
  }
  if (m > 0)
  {
    if (hud)
      hud->draw(image, order, lines, colours, m);
    else
      HudCache().draw(image, order, lines, colours, m);
  }
}
}  // namespace

bool drawOverlay(cv::Mat& image, ChannelOrder order, const RawProjector& camera, const OverlayStyle& style,
                 const ToolOverlay* tools, std::size_t n, ToolDrawResult* results, const char* status_line,
                 HudCache* hud)
{
  if (image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 4) || !camera.valid())
    return false;
  const CameraIntrinsics& k = camera.intrinsics();
  n = std::min(n, kMaxTools);
  const cv::Scalar outline(0, 0, 0, 255);
  for (std::size_t i = 0; i < n; ++i)
  {
    const ToolOverlay& tool = tools[i];
    ToolDrawResult r;
    r.proximity = classify(tool.distance, style);
    if (tool.visible)
    {
      const cv::Scalar colour = toScalar(colourOf(r.proximity, style), order);
      // The straight shaft is curved by the lens: projected as a polyline, all points at once.
      const int segments = tool.has_shaft ? style.shaft_segments : 0;
      cv::Point3d points[kMaxShaftSegments + 1];
      Projection proj[kMaxShaftSegments + 1];
      for (int s = 0; s <= segments; ++s)
        points[s] = tool.tip + (static_cast<double>(s) / std::max(1, segments)) * (tool.shaft - tool.tip);
      camera.project(points, static_cast<std::size_t>(segments) + 1, proj);
      const Projection& tip = proj[0];
      if (tool.has_shaft)
      {
        Projection prev = tip;
        for (int s = 1; s <= segments; ++s)
        {
          const Projection& cur = proj[s];
          if (prev.projectable && cur.projectable)
            cv::line(image, toFixedPoint(clampForDrawing(prev.pixel, k), kShift),
                     toFixedPoint(clampForDrawing(cur.pixel, k), kShift), colour, style.line_thickness,
                     cv::LINE_AA, kShift);
          prev = cur;
        }
        if (prev.in_image)
          cv::circle(image, toFixedPoint(prev.pixel, kShift), style.circle_radius << kShift, colour,
                     std::max(1, style.line_thickness - 1), cv::LINE_AA, kShift);
      }
      if (tip.in_image)
      {
        cv::circle(image, toFixedPoint(tip.pixel, kShift), style.circle_radius << kShift, colour, cv::FILLED,
                   cv::LINE_AA, kShift);
        r.drawn = ToolDrawn::kShaft;
        r.tip_pixel = tip.pixel;
      }
      else
      {
        // Out of view: a triangle at the image border pointing towards the tip.
        const double size = style.marker_size;
        const cv::Point2d c = borderPoint(tip.direction, k, size);
        cv::Point2d u = tip.direction;
        const double nu = std::hypot(u.x, u.y);
        u = (nu > 1e-12 && std::isfinite(nu)) ? u * (1.0 / nu) : cv::Point2d(0.0, 1.0);
        const cv::Point2d v(-u.y, u.x);
        const cv::Point pts[3] = {toFixedPoint(c + 0.9 * size * u, kShift),
                                  toFixedPoint(c - 0.5 * size * u + 0.6 * size * v, kShift),
                                  toFixedPoint(c - 0.5 * size * u - 0.6 * size * v, kShift)};
        cv::fillConvexPoly(image, pts, 3, colour, cv::LINE_AA, kShift);
        for (int e = 0; e < 3; ++e)
          cv::line(image, pts[e], pts[(e + 1) % 3], outline, 1, cv::LINE_AA, kShift);
        r.drawn = ToolDrawn::kBorderMarker;
        r.marker_pixel = c;
      }
    }
    if (results)
      results[i] = r;
  }

  drawHud(image, order, style, tools, n, status_line, hud);
  return true;
}

}  // namespace saras_visual_feedback
