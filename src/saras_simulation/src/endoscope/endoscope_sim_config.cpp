/**
 * @file endoscope_sim_config.cpp
 * @brief readEndoscopeConfig: the simulator's parameters through saras_common::Params; targets.
 */
#include "saras_simulation/endoscope_sim_config.h"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace saras_simulation
{
namespace endoscope
{
namespace
{
using saras_common::inRange;
using saras_common::nonEmpty;
using saras_common::oneOf;
using saras_common::Params;
using saras_common::positive;
using XmlRpc::XmlRpcValue;

/// A finite number inside a structured parameter (@p name for the message).
double finiteNumber(const Params& p, const std::string& name, XmlRpcValue& v, const std::string& unit)
{
  double x = NAN;
  if (v.getType() == XmlRpcValue::TypeInt)
    x = static_cast<int>(v);
  else if (v.getType() == XmlRpcValue::TypeDouble)
    x = static_cast<double>(v);
  else
    p.fail(name, Params::describe(v), unit, "a number");
  if (!std::isfinite(x))
    p.fail(name, x, unit, "finite");
  return x;
}

/// @p n finite numbers (a list entry of a structured parameter).
std::vector<double> numberList(const Params& p, const std::string& name, XmlRpcValue& v, size_t n,
                               const std::string& unit)
{
  if (v.getType() != XmlRpcValue::TypeArray || static_cast<size_t>(v.size()) != n)
    p.fail(name, Params::describe(v), unit, "a list of " + std::to_string(n) + " numbers");
  std::vector<double> out;
  for (int i = 0; i < v.size(); ++i)
    out.push_back(finiteNumber(p, name + "[" + std::to_string(i) + "]", v[i], unit));
  return out;
}

std::string expandUser(const std::string& path)
{
  if (!path.empty() && path[0] == '~')
  {
    const char* home = std::getenv("HOME");
    return std::string(home ? home : "") + path.substr(1);
  }
  return path;
}

/// ~tissue {z0 [m], centre [m, m], waves [[a m, kx rad/m, ky rad/m, phi rad]...]}
TissueSurface readTissue(const Params& p)
{
  XmlRpcValue t;
  if (!p.raw("tissue", t))
    return TissueSurface();
  if (t.getType() != XmlRpcValue::TypeStruct)
    p.fail("tissue", Params::describe(t), "", "a mapping {z0, centre, waves}");
  double z0 = 0.07;
  std::vector<double> c{ 0.0, 0.0 };
  std::vector<TissueSurface::Wave> waves = TissueSurface::defaultWaves();
  for (auto& kv : t)
  {
    const std::string name = "tissue/" + kv.first;
    if (kv.first == "z0")
      z0 = finiteNumber(p, name, kv.second, "m");
    else if (kv.first == "centre")
      c = numberList(p, name, kv.second, 2, "m");
    else if (kv.first == "waves")
    {
      if (kv.second.getType() != XmlRpcValue::TypeArray)
        p.fail(name, Params::describe(kv.second), "", "a list of [a m, kx rad/m, ky rad/m, phi rad]");
      waves.clear();
      for (int i = 0; i < kv.second.size(); ++i)
      {
        const auto w = numberList(p, name + "[" + std::to_string(i) + "]", kv.second[i], 4, "");
        waves.push_back({ w[0], w[1], w[2], w[3] });
      }
    }
    else
      p.fail(name, "set", "", "absent (keys: z0, centre, waves)");
  }
  return TissueSurface(z0, c[0], c[1], waves);
}

/// ~tools [{tip: frame, rcm: frame, radius: m}]
std::vector<ToolFrames> readTools(const Params& p)
{
  std::vector<ToolFrames> tools;
  XmlRpcValue v;
  if (!p.raw("tools", v))
    return tools;
  if (v.getType() != XmlRpcValue::TypeArray)
    p.fail("tools", Params::describe(v), "", "a list of {tip: frame, rcm: frame, radius: m}");
  for (int i = 0; i < v.size(); ++i)
  {
    XmlRpcValue& t = v[i];
    const std::string name = "tools[" + std::to_string(i) + "]";
    if (t.getType() != XmlRpcValue::TypeStruct || !t.hasMember("tip") || !t.hasMember("rcm") ||
        t["tip"].getType() != XmlRpcValue::TypeString || t["rcm"].getType() != XmlRpcValue::TypeString)
      p.fail(name, Params::describe(t), "", "{tip: frame, rcm: frame, radius: m}");
    ToolFrames tool{ static_cast<std::string>(t["tip"]), static_cast<std::string>(t["rcm"]), 0.004 };
    if (t.hasMember("radius"))
      tool.radius = finiteNumber(p, name + "/radius", t["radius"], "m");
    if (!(tool.radius > 0))
      p.fail(name + "/radius", tool.radius, "m", "> 0");
    tools.push_back(tool);
  }
  return tools;
}

/// Defaults of each target kind's numeric keys [m, counts].
const std::map<std::string, std::map<std::string, double>>& targetDefaults()
{
  static const std::map<std::string, std::map<std::string, double>> d{
    { "checkerboard", { { "cols", 8 }, { "rows", 6 }, { "square", 0.008 }, { "res", 0.0001 } } },
    { "circles",
      { { "dot_circle_radius", 0.100 }, { "dot_diameter", 0.005 }, { "dots", 8 }, { "marker_circle_radius", 0.060 },
        { "marker_side", 0.025 }, { "res", 0.0002 } } }
  };
  return d;
}

/// ~targets/<kind> {numeric keys of the kind, dictionary (circles), xyz [m], rpy [rad]}
TargetSpec readTarget(const Params& p, const std::string& kind, XmlRpcValue* spec)
{
  TargetSpec t;
  t.kind = kind;
  t.values = targetDefaults().at(kind);
  std::vector<double> xyz{ 0.0, 0.0, 0.085 }, rpy{ M_PI, 0.0, 0.0 };
  if (spec)
    for (auto& kv : *spec)
    {
      const std::string name = "targets/" + kind + "/" + kv.first;
      if (kv.first == "xyz")
        xyz = numberList(p, name, kv.second, 3, "m");
      else if (kv.first == "rpy")
        rpy = numberList(p, name, kv.second, 3, "rad");
      else if (kv.first == "dictionary" && kind == "circles" && kv.second.getType() == XmlRpcValue::TypeString)
        t.dictionary = static_cast<std::string>(kv.second);
      else if (t.values.count(kv.first))
        t.values[kv.first] = finiteNumber(p, name, kv.second, "");
      else
        p.fail(name, "set", "", "absent (not a key of a " + kind + " target)");
    }
  t.pose.linear() = rpyToMatrix(rpy[0], rpy[1], rpy[2]);
  t.pose.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  try
  {
    buildTarget(t);  // its sizes and dictionary are checked now, not when it is first shown
  }
  catch (const std::invalid_argument& e)
  {
    p.fail("targets/" + kind, "a " + kind + " target", "", std::string("buildable (") + e.what() + ")");
  }
  return t;
}

std::map<std::string, TargetSpec> readTargets(const Params& p)
{
  XmlRpcValue v;
  const bool set = p.raw("targets", v);
  if (set && v.getType() != XmlRpcValue::TypeStruct)
    p.fail("targets", Params::describe(v), "", "a mapping {checkerboard: {...}, circles: {...}}");
  std::map<std::string, TargetSpec> out;
  for (const auto& kd : targetDefaults())
  {
    XmlRpcValue* spec = nullptr;
    if (set && v.hasMember(kd.first))
    {
      spec = &v[kd.first];
      if (spec->getType() != XmlRpcValue::TypeStruct)
        p.fail("targets/" + kd.first, Params::describe(*spec), "", "a mapping");
    }
    out[kd.first] = readTarget(p, kd.first, spec);
  }
  if (set)
    for (auto& kv : v)
      if (!targetDefaults().count(kv.first))
        p.fail("targets/" + kv.first, "set", "", "absent (targets: checkerboard, circles)");
  return out;
}
}  // namespace

std::shared_ptr<PlanarTarget> buildTarget(const TargetSpec& spec)
{
  const auto& v = spec.values;
  if (spec.kind == "checkerboard")
    return std::make_shared<PlanarTarget>(PlanarTarget::checkerboard(int(v.at("cols")), int(v.at("rows")),
                                                                     v.at("square"), v.at("res")));
  if (spec.kind == "circles")
    return std::make_shared<PlanarTarget>(PlanarTarget::circles(v.at("dot_circle_radius"), v.at("dot_diameter"),
                                                                int(v.at("dots")), v.at("marker_circle_radius"),
                                                                v.at("marker_side"), v.at("res"), spec.dictionary));
  throw std::invalid_argument("unknown target '" + spec.kind + "' (checkerboard | circles)");
}

EndoscopeConfig readEndoscopeConfig(const Params& p)
{
  EndoscopeConfig c;
  c.fps = p.number("fps", 30.0, "Hz", { inRange(0.5, 120.0) });
  c.width = p.integer("width", 1280, "px", { inRange(16, 7680) });
  c.height = p.integer("height", 720, "px", { inRange(16, 4320) });
  const std::string dir = expandUser(p.text("camera_info_dir", ""));
  const char* const eyes[2] = { "left", "right" };
  for (int e = 0; e < 2; ++e)
  {
    const std::string file = p.text(std::string(eyes[e]) + "_camera_info", std::string("endoscope_") + eyes[e] + ".yaml",
                                     { nonEmpty() });
    c.camera_info[e] = file[0] == '/' ? file : dir + "/" + file;
    c.frames[e] = p.text(std::string(eyes[e]) + "_frame", c.frames[e], { nonEmpty() });
  }
  c.world = p.text("world_frame", c.world, { nonEmpty() });
  c.jpeg_quality = p.integer("jpeg_quality", 85, "", { inRange(1, 100) });
  c.recorded_queue = p.integer("recorded_queue", 30, "messages", { inRange(1, 1000) });
  c.tf_timeout = p.number("tf_timeout", 0.5, "s", { positive() });
  c.parallel_eyes = p.flag("parallel_eyes", true);
  c.renderer.texture_size = p.integer("texture_size", 1024, "texels", { inRange(16, 8192) });
  c.renderer.texture_extent = p.number("texture_extent", 0.30, "m", { positive() });
  c.renderer.light_distance = p.number("light_distance", 0.10, "m", { positive() });
  c.tissue = readTissue(p);
  c.tools = readTools(p);
  c.bones_file = expandUser(p.text("bones_file", ""));
  c.bones_frame = p.text("bones_frame", c.bones_frame, { nonEmpty() });
  c.bones_scaling = p.number("bones_scaling", 1.0, "m per file unit", { positive() });
  c.targets = readTargets(p);
  c.initial_target = p.text("target", "none", { oneOf({ "none", "checkerboard", "circles" }) });
  return c;
}

}  // namespace endoscope
}  // namespace saras_simulation
