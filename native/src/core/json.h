// The JSON type used for reports (nlohmann::json, Debian's nlohmann-json3-dev).
#pragma once
#include <nlohmann/json.hpp>

namespace qgp {
using Json = nlohmann::ordered_json;
}
