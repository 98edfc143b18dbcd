/**
 * @file nodelet_namespace.h
 * @brief Namespace for the topics of a nodelet: those of the standalone node, whatever the manager.
 */
#ifndef SARAS_COMMON_NODELET_NAMESPACE_H
#define SARAS_COMMON_NODELET_NAMESPACE_H

#include <string>

#include <ros/names.h>

namespace saras_common
{
/**
 * Absolute namespace of the nodelet named @p nodelet_name, with a trailing '/' (e.g. "/endoscope/"
 * for "/endoscope/endoscope_sim", "/" for "/touchball_receiver"). The nodelet NodeHandle of a
 * nodelet resolves relative names in the MANAGER's namespace (e.g. /teleop when loaded into
 * /teleop/teleop_manager), which would move the topics with the manager; names built on this
 * prefix stay those of the standalone node. Remappings still apply (they act on resolved names).
 */
inline std::string nodeletNamespace(const std::string& nodelet_name)
{
  std::string ns = ros::names::parentNamespace(nodelet_name);
  if (ns.empty() || ns.back() != '/')
    ns += '/';
  return ns;
}

}  // namespace saras_common

#endif  // SARAS_COMMON_NODELET_NAMESPACE_H
