#include <cmath>
#include <stdexcept>
#include <string>

#include <XmlRpcValue.h>

#include "saras_visual_feedback/contact_estimator_nodelet.h"
#include "xml_fields.h"

namespace saras_visual_feedback
{
namespace
{
using detail::paramError;
using detail::xmlNumber;
using detail::xmlString;

ContactToolConfig readTool(XmlRpc::XmlRpcValue& v, const std::string& where)
{
  if (v.getType() != XmlRpc::XmlRpcValue::TypeStruct)
    throw paramError(where, "must be a dictionary");
  ContactToolConfig t;
  t.tool.name = xmlString(v, "name", where, true);
  t.tool.label = t.tool.name;
  t.tool.pose_topic = xmlString(v, "pose_topic", where, true);
  t.tool.rcm_frame = xmlString(v, "rcm_frame", where, false);
  t.radius = xmlNumber(v, "radius", t.radius, where);
  if (!(std::isfinite(t.radius) && t.radius > 0.0))
    throw paramError(where, "'radius' must be > 0 [m]");
  if (v.hasMember("estimate"))
  {
    if (v["estimate"].getType() != XmlRpc::XmlRpcValue::TypeBoolean)
      throw paramError(where, "'estimate' must be a boolean");
    t.estimate = static_cast<bool>(v["estimate"]);
  }
  t.topic = xmlString(v, "topic", where, t.estimate);
  t.direction_frame = xmlString(v, "direction_frame", where, t.estimate);
  return t;
}

void readEstimator(const ros::NodeHandle& pnh, StereoContactParams* e)
{
  pnh.param("patch_radius", e->patch_radius, e->patch_radius);
  pnh.param("near_margin", e->near_margin, e->near_margin);
  pnh.param("far_margin", e->far_margin, e->far_margin);
  pnh.param("block_size", e->block_size, e->block_size);
  pnh.param("texture_threshold", e->texture_threshold, e->texture_threshold);
  pnh.param("uniqueness_ratio", e->uniqueness_ratio, e->uniqueness_ratio);
  pnh.param("mask_margin", e->mask_margin, e->mask_margin);
  pnh.param("min_points", e->min_points, e->min_points);
  pnh.param("min_valid_fraction", e->min_valid_fraction, e->min_valid_fraction);
  pnh.param("max_masked_fraction", e->max_masked_fraction, e->max_masked_fraction);
  pnh.param("inlier_threshold", e->inlier_threshold, e->inlier_threshold);
  pnh.param("min_inlier_ratio", e->min_inlier_ratio, e->min_inlier_ratio);
  pnh.param("ransac_iterations", e->ransac_iterations, e->ransac_iterations);
  pnh.param("refine_iterations", e->refine_iterations, e->refine_iterations);
  pnh.param("contact_threshold", e->contact_threshold, e->contact_threshold);
  pnh.param("max_roi", e->max_roi, e->max_roi);
  pnh.param("sample_grid", e->sample_grid, e->sample_grid);
  std::string why;
  if (!validateStereoContactParams(*e, &why))
    throw paramError(why.substr(0, why.find(' ')), why);
}
}  // namespace

ContactEstimatorParams readContactEstimatorParams(const ros::NodeHandle& pnh)
{
  ContactEstimatorParams p;
  readEstimator(pnh, &p.estimator);
  pnh.param("pose_timeout", p.pose_timeout, p.pose_timeout);
  pnh.param("pose_stamp_tolerance", p.pose_stamp_tolerance, p.pose_stamp_tolerance);
  pnh.param("image_timeout", p.image_timeout, p.image_timeout);
  pnh.param("pose_buffer_size", p.pose_buffer_size, p.pose_buffer_size);
  pnh.param("queue_size", p.queue_size, p.queue_size);
  if (!(std::isfinite(p.pose_timeout) && p.pose_timeout > 0.0))
    throw paramError("pose_timeout", "must be > 0 [s]");
  if (!(std::isfinite(p.pose_stamp_tolerance) && p.pose_stamp_tolerance >= 0.0))
    throw paramError("pose_stamp_tolerance", "must be >= 0 [s]");
  if (!(std::isfinite(p.image_timeout) && p.image_timeout > 0.0))
    throw paramError("image_timeout", "must be > 0 [s]");
  if (p.pose_buffer_size < 2 || p.pose_buffer_size > 100000)
    throw paramError("pose_buffer_size", "must be in [2, 100000] samples");
  if (p.queue_size < 1)
    throw paramError("queue_size", "must be >= 1");
  XmlRpc::XmlRpcValue list;
  if (!pnh.getParam("tools", list) || list.getType() != XmlRpc::XmlRpcValue::TypeArray || list.size() < 1 ||
      list.size() > static_cast<int>(kMaxTools))
    throw paramError("tools", "must be a list of 1 to " + std::to_string(kMaxTools) + " tools");
  for (int i = 0; i < list.size(); ++i)
  {
    p.tools.push_back(readTool(list[i], "tools[" + std::to_string(i) + "]"));
    p.tools.back().tool.distance_index = i;
  }
  return p;
}

}  // namespace saras_visual_feedback
