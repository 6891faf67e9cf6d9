#include "pipeline/options.h"

#include "core/error.h"

namespace qgp {

Quantizer parse_quantizer(const std::string& name) {
  if (name == "greedy") return Quantizer::Greedy;
  if (name == "round") return Quantizer::Round;
  throw Error(ErrorCode::InvalidArgument, "unknown quantizer '" + name + "' (use greedy or round)");
}

const char* quantizer_name(Quantizer q) { return q == Quantizer::Greedy ? "greedy" : "round"; }

}  // namespace qgp
