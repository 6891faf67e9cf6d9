// The JSON type used for reports (nlohmann::json, Debian's nlohmann-json3-dev), keeping keys in the
// order they are written.
//
// Every stats struct maps to JSON once, as to_json(Json&, const T&) next to its declaration, so that
// `Json j = stats;` works everywhere. Where the report keys are the members' names, declare it with
// QGP_JSON_FIELDS(T, member, ...) (nlohmann's NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE, for this Json).
#pragma once
#include <nlohmann/json.hpp>

namespace qgp {
using Json = nlohmann::ordered_json;
}

// Defines to_json(qgp::Json&, const Type&) writing the listed members, in order, under their names.
// Use inside the namespace of Type.
#define QGP_JSON_FIELDS(Type, ...)                                                 \
  inline void to_json(::qgp::Json& nlohmann_json_j, const Type& nlohmann_json_t) { \
    NLOHMANN_JSON_EXPAND(NLOHMANN_JSON_PASTE(NLOHMANN_JSON_TO, __VA_ARGS__))       \
  }
