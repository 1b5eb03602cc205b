#include "shape/Section.hpp"
#include "core/Errors.hpp"

namespace woven {

SectionRule sectionRuleByName(const std::string& name) {
  if (name == "paper") return SectionRule::Paper;
  if (name == "constant_area") return SectionRule::ConstantArea;
  throw ParameterError("section_rule", "'" + name + "'", "'paper' (a = r0(1+eps), b = r0(1-eps)) or 'constant_area' (a*b = r0^2)");
}

const char* sectionRuleName(SectionRule r) { return r == SectionRule::Paper ? "paper" : "constant_area"; }

}  // namespace woven
