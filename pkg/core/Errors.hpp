// Error types. Every invalid input names its parameter and the allowed range; every instability
// names the step, the node (or element) and the cause, so a user can find what went wrong.
#pragma once
#include <sstream>
#include <stdexcept>
#include <string>

namespace woven {

/// Invalid user input: `parameter` is the public parameter name, `allowed` the allowed range.
class ParameterError : public std::invalid_argument {
 public:
  ParameterError(const std::string& parameter, const std::string& value, const std::string& allowed)
      : std::invalid_argument(parameter + " = " + value + " is invalid: allowed " + allowed),
        parameter_(parameter) {}
  const std::string& parameter() const { return parameter_; }

 private:
  std::string parameter_;
};

/// Helper that formats a number the way the error messages print it.
template <class T>
std::string fmt(const T& v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

/// Throws ParameterError unless `ok`.
inline void require(bool ok, const std::string& parameter, double value, const std::string& allowed) {
  if (!ok) throw ParameterError(parameter, fmt(value), allowed);
}

/// A simulation went unstable. The state at the last check point is kept by the Fabric.
class InstabilityError : public std::runtime_error {
 public:
  InstabilityError(long step, long node, long element, const std::string& cause)
      : std::runtime_error(describe(step, node, element, cause)), step_(step), node_(node),
        element_(element), cause_(cause) {}
  long step() const { return step_; }
  long node() const { return node_; }        ///< -1 when the cause is an element
  long element() const { return element_; }  ///< -1 when the cause is a node
  const std::string& cause() const { return cause_; }

 private:
  static std::string describe(long step, long node, long element, const std::string& cause) {
    std::ostringstream s;
    s << "woven: simulation unstable at step " << step;
    if (node >= 0) s << ", node " << node;
    if (element >= 0) s << ", element " << element;
    s << ": " << cause << " (the last good state is kept: Fabric.restore_last_good / save_state)";
    return s.str();
  }
  long step_, node_, element_;
  std::string cause_;
};

}  // namespace woven
