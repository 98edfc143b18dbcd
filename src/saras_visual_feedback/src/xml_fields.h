/**
 * @file xml_fields.h
 * @brief Internal to the package's parameter readers (visual_feedback_params.cpp,
 *        contact_estimator_params.cpp): the start-up error and the typed fields of a structured
 *        (XmlRpc dictionary) parameter such as one entry of ~tools.
 */
#ifndef SARAS_VISUAL_FEEDBACK_XML_FIELDS_H
#define SARAS_VISUAL_FEEDBACK_XML_FIELDS_H

#include <stdexcept>
#include <string>

#include <XmlRpcValue.h>

namespace saras_visual_feedback
{
namespace detail
{
/// A start-up parameter error: names the parameter; makes onInit fail (the node exits non-zero).
inline std::runtime_error paramError(const std::string& name, const std::string& why)
{
  return std::runtime_error("invalid parameter ~" + name + ": " + why);
}

/// String field @p key of dictionary @p v (parameter @p where); @p def when absent and not required.
inline std::string xmlString(XmlRpc::XmlRpcValue& v, const std::string& key, const std::string& where,
                             bool required, const std::string& def = "")
{
  if (!v.hasMember(key))
  {
    if (required)
      throw paramError(where, "missing '" + key + "'");
    return def;
  }
  if (v[key].getType() != XmlRpc::XmlRpcValue::TypeString)
    throw paramError(where, "'" + key + "' must be a string");
  return static_cast<std::string>(v[key]);
}

/// Number field @p key of dictionary @p v (an integer is accepted); @p def when absent.
inline double xmlNumber(XmlRpc::XmlRpcValue& v, const std::string& key, double def, const std::string& where)
{
  if (!v.hasMember(key))
    return def;
  if (v[key].getType() == XmlRpc::XmlRpcValue::TypeInt)
    return static_cast<int>(v[key]);
  if (v[key].getType() != XmlRpc::XmlRpcValue::TypeDouble)
    throw paramError(where, "'" + key + "' must be a number");
  return static_cast<double>(v[key]);
}
}  // namespace detail
}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_XML_FIELDS_H
