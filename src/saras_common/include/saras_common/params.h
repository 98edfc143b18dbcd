/**
 * @file params.h
 * @brief Typed, validated start-up parameters with units (header only).
 *
 * A node reads each parameter once, at start-up, into its configuration struct:
 * @code
 *   saras_common::Params p(pnh);                                   // private NodeHandle
 *   cfg.timeout = p.number("timeout", 0.03, "s", { saras_common::positive() });
 *   cfg.port = p.integer("port", 5005, "", { saras_common::inRange(0, 65535) });
 *   cfg.mode = p.text("mode", "shared", { saras_common::oneOf({ "manager", "shared" }) });
 *   cfg.gains = p.numbers("gains", { 1, 1, 1 }, "N/m", { saras_common::nonNegative() }, 3);
 *   if (cfg.resync_after < cfg.timeout)                            // a rule across parameters
 *     p.fail("resync_after", cfg.resync_after, "s", ">= timeout");
 * @endcode
 * An absent parameter takes its default; a present one must have the right type (an integer is
 * accepted where a number is expected, nothing else is converted). Numbers must be finite and satisfy
 * every rule given. A violation throws ParamError, whose message names the resolved parameter, its
 * value, its unit and the rule, e.g.
 * `parameter /teleop/tank_master/timeout = -1 [s] is invalid: must be > 0`.
 * Nodelets let it escape onInit(), so the manager refuses them and `nodelet load` / `nodelet
 * standalone` exit non-zero.
 *
 * The checks are ROS-free: Params reads through a lookup function (a ros::NodeHandle's getParam()
 * for nodes, a map in tests).
 */
#ifndef SARAS_COMMON_PARAMS_H
#define SARAS_COMMON_PARAMS_H

#include <cmath>
#include <cstddef>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

namespace saras_common
{
/// A start-up parameter that is missing its type or breaks a rule.
class ParamError : public std::invalid_argument
{
public:
  /**
   * @param name resolved parameter name
   * @param value the offending value as text
   * @param unit unit of the value ("" for none)
   * @param rule what the value must be ("> 0", "a number", "one of manager, shared")
   */
  ParamError(const std::string& name, const std::string& value, const std::string& unit, const std::string& rule)
    : std::invalid_argument("parameter " + name + " = " + value + (unit.empty() ? "" : " [" + unit + "]") +
                            " is invalid: must be " + rule)
    , name_(name)
    , rule_(rule)
  {
  }
  const std::string& name() const { return name_; }
  const std::string& rule() const { return rule_; }

private:
  std::string name_;
  std::string rule_;
};

/// A number in shortest round-trip-ish form for messages ("0.03", "-1", "1e+300").
inline std::string formatNumber(double v)
{
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

/// A rule a number must satisfy; `text` completes "must be ...".
struct NumberRule
{
  std::function<bool(double)> holds;
  std::string text;
};

inline NumberRule positive()
{
  return { [](double v) { return v > 0.0; }, "> 0" };
}
inline NumberRule nonNegative()
{
  return { [](double v) { return v >= 0.0; }, ">= 0" };
}
inline NumberRule atLeast(double lo)
{
  return { [lo](double v) { return v >= lo; }, ">= " + formatNumber(lo) };
}
inline NumberRule atMost(double hi)
{
  return { [hi](double v) { return v <= hi; }, "<= " + formatNumber(hi) };
}
/// lo <= v <= hi
inline NumberRule inRange(double lo, double hi)
{
  return { [lo, hi](double v) { return v >= lo && v <= hi; },
           "in [" + formatNumber(lo) + ", " + formatNumber(hi) + "]" };
}

/// A rule a string must satisfy; `text` completes "must be ...".
struct TextRule
{
  std::function<bool(const std::string&)> holds;
  std::string text;
};

inline TextRule nonEmpty()
{
  return { [](const std::string& v) { return !v.empty(); }, "non-empty" };
}
inline TextRule oneOf(const std::vector<std::string>& options)
{
  std::string text = "one of";
  for (std::size_t i = 0; i < options.size(); ++i)
    text += (i == 0 ? " " : ", ") + options[i];
  return { [options](const std::string& v) {
            for (const std::string& o : options)
              if (v == o)
                return true;
            return false;
          },
           text };
}

/// Reads typed parameters once and validates them (see the file comment).
class Params
{
public:
  /// Fetch a parameter by (relative) name; false if it is not set.
  using Lookup = std::function<bool(const std::string& name, XmlRpc::XmlRpcValue& value)>;
  /// The full name of a parameter, for messages.
  using Resolve = std::function<std::string(const std::string& name)>;

  Params(Lookup lookup, Resolve resolve) : lookup_(std::move(lookup)), resolve_(std::move(resolve)) {}

  /// Parameters of a NodeHandle (usually the private one, names relative to it).
  explicit Params(const ros::NodeHandle& nh)
    : Params([nh](const std::string& n, XmlRpc::XmlRpcValue& v) { return nh.getParam(n, v); },
             [nh](const std::string& n) { return nh.resolveName(n); })
  {
  }

  /// The full name of @p name.
  std::string resolve(const std::string& name) const { return resolve_(name); }

  /// Whether @p name is set.
  bool has(const std::string& name) const
  {
    XmlRpc::XmlRpcValue x;
    return lookup_(name, x);
  }

  /// The raw value of a structured parameter (lists of dictionaries ...); false if not set.
  bool raw(const std::string& name, XmlRpc::XmlRpcValue& value) const { return lookup_(name, value); }

  /// Throw ParamError for @p name (rules across parameters, structured parameters).
  [[noreturn]] void fail(const std::string& name, const std::string& value, const std::string& unit,
                         const std::string& rule) const
  {
    throw ParamError(resolve_(name), value, unit, rule);
  }
  [[noreturn]] void fail(const std::string& name, double value, const std::string& unit, const std::string& rule) const
  {
    fail(name, formatNumber(value), unit, rule);
  }

  /// A finite number (integer or floating point) satisfying @p rules; @p unit for messages.
  double number(const std::string& name, double def, const std::string& unit,
                std::initializer_list<NumberRule> rules = {}) const
  {
    double v = def;
    XmlRpc::XmlRpcValue x;
    if (lookup_(name, x) && !toNumber(x, v))
      fail(name, describe(x), unit, "a number");
    check(name, v, unit, rules);
    return v;
  }

  /// An integer satisfying @p rules.
  int integer(const std::string& name, int def, const std::string& unit, std::initializer_list<NumberRule> rules = {}) const
  {
    int v = def;
    XmlRpc::XmlRpcValue x;
    if (lookup_(name, x))
    {
      if (x.getType() != XmlRpc::XmlRpcValue::TypeInt)
        fail(name, describe(x), unit, "an integer");
      v = static_cast<int>(x);
    }
    check(name, v, unit, rules);
    return v;
  }

  /// true or false.
  bool flag(const std::string& name, bool def) const
  {
    XmlRpc::XmlRpcValue x;
    if (!lookup_(name, x))
      return def;
    if (x.getType() != XmlRpc::XmlRpcValue::TypeBoolean)
      fail(name, describe(x), "", "true or false");
    return static_cast<bool>(x);
  }

  /// A string satisfying @p rules.
  std::string text(const std::string& name, const std::string& def, std::initializer_list<TextRule> rules = {}) const
  {
    std::string v = def;
    XmlRpc::XmlRpcValue x;
    if (lookup_(name, x))
    {
      if (x.getType() != XmlRpc::XmlRpcValue::TypeString)
        fail(name, describe(x), "", "a string");
      v = static_cast<std::string>(x);
    }
    checkText(name, v, rules);
    return v;
  }

  /**
   * A list of finite numbers, each satisfying @p rules. With @p size > 0 the list must have exactly
   * that many entries, or be one number used for every entry; with 0 any length is accepted.
   */
  std::vector<double> numbers(const std::string& name, const std::vector<double>& def, const std::string& unit,
                              std::initializer_list<NumberRule> rules = {}, std::size_t size = 0) const
  {
    std::vector<double> v = def;
    XmlRpc::XmlRpcValue x;
    if (lookup_(name, x))
    {
      const std::string shape = size > 0 ? "a list of " + std::to_string(size) + " numbers or one number" : "a list of numbers";
      double scalar = 0.0;
      if (size > 0 && toNumber(x, scalar))
        v.assign(size, scalar);
      else if (x.getType() != XmlRpc::XmlRpcValue::TypeArray || (size > 0 && static_cast<std::size_t>(x.size()) != size))
        fail(name, describe(x), unit, shape);
      else
      {
        v.resize(static_cast<std::size_t>(x.size()));
        for (int i = 0; i < x.size(); ++i)
          if (!toNumber(x[i], v[static_cast<std::size_t>(i)]))
            fail(name, describe(x), unit, shape);
      }
    }
    for (std::size_t i = 0; i < v.size(); ++i)
      check(name + "[" + std::to_string(i) + "]", v[i], unit, rules);
    return v;
  }

  /// A list of strings, each satisfying @p rules.
  std::vector<std::string> texts(const std::string& name, const std::vector<std::string>& def,
                                 std::initializer_list<TextRule> rules = {}) const
  {
    std::vector<std::string> v = def;
    XmlRpc::XmlRpcValue x;
    if (lookup_(name, x))
    {
      if (x.getType() != XmlRpc::XmlRpcValue::TypeArray)
        fail(name, describe(x), "", "a list of strings");
      v.clear();
      for (int i = 0; i < x.size(); ++i)
      {
        if (x[i].getType() != XmlRpc::XmlRpcValue::TypeString)
          fail(name, describe(x), "", "a list of strings");
        v.push_back(static_cast<std::string>(x[i]));
      }
    }
    for (std::size_t i = 0; i < v.size(); ++i)
      checkText(name + "[" + std::to_string(i) + "]", v[i], rules);
    return v;
  }

  /// A parameter value as text for messages ('abc', 3, 0.5, true, a list of 2, a dictionary).
  static std::string describe(XmlRpc::XmlRpcValue& x)
  {
    switch (x.getType())
    {
      case XmlRpc::XmlRpcValue::TypeInt:
        return std::to_string(static_cast<int>(x));
      case XmlRpc::XmlRpcValue::TypeDouble:
        return formatNumber(static_cast<double>(x));
      case XmlRpc::XmlRpcValue::TypeBoolean:
        return static_cast<bool>(x) ? "true" : "false";
      case XmlRpc::XmlRpcValue::TypeString:
        return "'" + static_cast<std::string>(x) + "'";
      case XmlRpc::XmlRpcValue::TypeArray:
        return "a list of " + std::to_string(x.size());
      case XmlRpc::XmlRpcValue::TypeStruct:
        return "a dictionary";
      default:
        return "a value of XmlRpc type " + std::to_string(static_cast<int>(x.getType()));
    }
  }

private:
  static bool toNumber(XmlRpc::XmlRpcValue& x, double& out)
  {
    if (x.getType() == XmlRpc::XmlRpcValue::TypeInt)
      out = static_cast<int>(x);
    else if (x.getType() == XmlRpc::XmlRpcValue::TypeDouble)
      out = static_cast<double>(x);
    else
      return false;
    return true;
  }

  void check(const std::string& name, double v, const std::string& unit, std::initializer_list<NumberRule> rules) const
  {
    bool ok = std::isfinite(v);
    std::string all;
    for (const NumberRule& r : rules)
    {
      ok = ok && r.holds(v);
      all += (all.empty() ? "" : " and ") + r.text;
    }
    if (!std::isfinite(v))
      all = all.empty() ? "finite" : "finite and " + all;
    if (!ok)
      fail(name, v, unit, all);
  }

  void checkText(const std::string& name, const std::string& v, std::initializer_list<TextRule> rules) const
  {
    for (const TextRule& r : rules)
      if (!r.holds(v))
        fail(name, "'" + v + "'", "", r.text);
  }

  Lookup lookup_;
  Resolve resolve_;
};

}  // namespace saras_common

#endif  // SARAS_COMMON_PARAMS_H
