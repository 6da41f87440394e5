// identification_methods.cpp — the names of identify()'s methods, gain sources and algorithms (identification.h).
#include "manipid/core/paper/identification.h"

#include "estimation/optimizer.h"

namespace manipid {

const char* to_string(IdentificationMethod method) {
  switch (method) {
    case IdentificationMethod::output_error: return "output-error";
    case IdentificationMethod::two_stage: return "two-stage";
    default: return "input-error";
  }
}

IdentificationMethod parse_identification_method(const std::string& text, const std::string& field) {
  if (text == "input-error") return IdentificationMethod::input_error;
  if (text == "output-error") return IdentificationMethod::output_error;
  if (text == "two-stage") return IdentificationMethod::two_stage;
  throw InputError(field, "unknown method '" + text + "' (expected input-error, output-error or two-stage)");
}

const char* to_string(GainSource source) {
  switch (source) {
    case GainSource::given: return "given";
    case GainSource::estimated: return "estimated";
    case GainSource::assumed: return "assumed";
    default: return "none";
  }
}

std::vector<std::string> identification_algorithms() {
  return {detail::kLeastSquaresAlgorithm, "LN_BOBYQA", "LN_NELDERMEAD", "LN_SBPLX", "LD_LBFGS", "LD_SLSQP"};
}

std::string default_algorithm(IdentificationMethod method) {
  // Input-error's cost is |R β(θ) − z|² with an exact Jacobian: LM takes 10–24 evaluations on the paper case
  // where LN_BOBYQA takes 1,500–1,700. Output-error's has no Jacobian short of finite differences of simulations.
  return method == IdentificationMethod::output_error ? "LN_BOBYQA" : detail::kLeastSquaresAlgorithm;
}

std::string resolve_algorithm(IdentificationMethod method, const std::string& algorithm) {
  const std::string name = algorithm.empty() ? default_algorithm(method) : algorithm;
  const bool derivatives = detail::algorithm_uses_gradient(name);  // throws on unknown names
  if (method == IdentificationMethod::output_error && derivatives) {
    throw InputError("algorithm", "output-error runs derivative-free algorithms only (LN_BOBYQA, LN_NELDERMEAD, "
                                  "LN_SBPLX), got " + name);
  }
  return name;
}

}  // namespace manipid
