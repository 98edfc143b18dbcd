#include "saras_visual_feedback/visual_feedback_params.h"
#include "xml_fields.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <XmlRpcValue.h>

namespace saras_visual_feedback
{
namespace
{
using detail::paramError;
using detail::xmlString;

double readPositive(const ros::NodeHandle& pnh, const std::string& name, double def, const char* unit)
{
  double v = def;
  pnh.param(name, v, def);
  if (!(std::isfinite(v) && v > 0.0))
    throw paramError(name, "must be finite and > 0 " + std::string(unit) + ", got " + std::to_string(v));
  return v;
}

SceneStyle readStyle(const ros::NodeHandle& pnh)
{
  SceneStyle style;
  OverlayStyle& s = style.overlay;
  pnh.param("collision_threshold", s.collision_threshold, s.collision_threshold);
  pnh.param("warning_threshold", s.warning_threshold, s.warning_threshold);
  const char* colour_names[4] = {"collision_colour", "warning_colour", "safe_colour", "unknown_colour"};
  Rgb* colours[4] = {&s.collision_colour, &s.warning_colour, &s.safe_colour, &s.unknown_colour};
  for (int i = 0; i < 4; ++i)
  {
    std::string text;
    if (pnh.getParam(colour_names[i], text) && !parseColour(text, colours[i]))
      throw paramError(colour_names[i], "must be \"#RRGGBB\", got \"" + text + "\"");
  }
  pnh.param("line_thickness", s.line_thickness, s.line_thickness);
  pnh.param("circle_radius", s.circle_radius, s.circle_radius);
  pnh.param("marker_size", s.marker_size, s.marker_size);
  pnh.param("shaft_segments", s.shaft_segments, s.shaft_segments);
  pnh.param("draw_hud", s.draw_hud, s.draw_hud);
  std::string why;
  if (!validateStyle(s, &why))
    throw paramError(why.substr(0, why.find(' ')), why);
  style.shaft_length = readPositive(pnh, "shaft_length", 0.05, "[m]");
  pnh.param("draw_dvrk", style.draw_dvrk, true);
  return style;
}

/// The platform's tools: the contract's topics and frames.
XmlRpc::XmlRpcValue defaultTools()
{
  XmlRpc::XmlRpcValue list;
  list.setSize(0);
  const char* names[4] = {"mesa_left", "mesa_right", "PSM1", "PSM2"};
  const char* topics[4] = {"/mesa_left/ee_pose", "/mesa_right/ee_pose", "/dvrk/PSM1/position_cartesian_current",
                           "/dvrk/PSM2/position_cartesian_current"};
  const char* rcm[4] = {"mesa_left/rcm", "mesa_right/rcm", "PSM1", "PSM2"};
  for (int i = 0; i < 4; ++i)
  {
    list[i]["name"] = std::string(names[i]);
    list[i]["pose_topic"] = std::string(topics[i]);
    list[i]["rcm_frame"] = std::string(rcm[i]);
    list[i]["distance_index"] = i;
    list[i]["dvrk"] = i >= 2;
  }
  return list;
}

ToolConfig readTool(XmlRpc::XmlRpcValue& v, const std::string& where)
{
  if (v.getType() != XmlRpc::XmlRpcValue::TypeStruct)
    throw paramError(where, "must be a dictionary");
  ToolConfig t;
  t.name = xmlString(v, "name", where, true);
  t.label = xmlString(v, "label", where, false, t.name);
  t.pose_topic = xmlString(v, "pose_topic", where, true);
  t.rcm_frame = xmlString(v, "rcm_frame", where, false);
  if (!v.hasMember("distance_index") || v["distance_index"].getType() != XmlRpc::XmlRpcValue::TypeInt ||
      static_cast<int>(v["distance_index"]) < 0)
    throw paramError(where, "'distance_index' must be an integer >= 0 (index in /collision/distances)");
  t.distance_index = static_cast<int>(v["distance_index"]);
  if (v.hasMember("dvrk"))
  {
    if (v["dvrk"].getType() != XmlRpc::XmlRpcValue::TypeBoolean)
      throw paramError(where, "'dvrk' must be a boolean");
    t.dvrk = static_cast<bool>(v["dvrk"]);
  }
  if (t.name.empty() || t.pose_topic.empty())
    throw paramError(where, "'name' and 'pose_topic' must not be empty");
  return t;
}
}  // namespace

VisualFeedbackParams readVisualFeedbackParams(const ros::NodeHandle& pnh)
{
  VisualFeedbackParams p;
  p.style = readStyle(pnh);
  p.pose_timeout = readPositive(pnh, "pose_timeout", p.pose_timeout, "[s]");
  p.distances_timeout = readPositive(pnh, "distances_timeout", p.distances_timeout, "[s]");
  p.image_timeout = readPositive(pnh, "image_timeout", p.image_timeout, "[s]");
  pnh.param("pose_buffer_size", p.pose_buffer_size, p.pose_buffer_size);
  if (p.pose_buffer_size < 2 || p.pose_buffer_size > 100000)
    throw paramError("pose_buffer_size", "must be in [2, 100000] samples, got " + std::to_string(p.pose_buffer_size));
  pnh.param("pose_stamp_tolerance", p.pose_stamp_tolerance, p.pose_stamp_tolerance);
  if (!(std::isfinite(p.pose_stamp_tolerance) && p.pose_stamp_tolerance >= 0.0))
    throw paramError("pose_stamp_tolerance",
                     "must be finite and >= 0 [s], got " + std::to_string(p.pose_stamp_tolerance));
  pnh.param("jpeg_quality", p.jpeg_quality, p.jpeg_quality);
  if (p.jpeg_quality < 1 || p.jpeg_quality > 100)
    throw paramError("jpeg_quality", "must be in [1, 100], got " + std::to_string(p.jpeg_quality));
  pnh.param("queue_size", p.queue_size, p.queue_size);
  if (p.queue_size < 1)
    throw paramError("queue_size", "must be >= 1");

  XmlRpc::XmlRpcValue list;
  if (!pnh.getParam("tools", list))
    list = defaultTools();
  if (list.getType() != XmlRpc::XmlRpcValue::TypeArray || list.size() < 1 ||
      list.size() > static_cast<int>(kMaxTools))
    throw paramError("tools", "must be a list of 1 to " + std::to_string(kMaxTools) + " tools");
  for (int i = 0; i < list.size(); ++i)
    p.tools.push_back(readTool(list[i], "tools[" + std::to_string(i) + "]"));
  return p;
}

}  // namespace saras_visual_feedback
