// swf-eval's JSON, on nlohmann::ordered_json (fields keep the order they are set in), written
// through swf::ground_cli::WriteJson (whole or not at all). Numbers go through SetNumber, so a
// non-finite value (a diverged estimate, a ratio of two zeros) is written as null with a
// "<key>_reason" string beside it: JSON has no inf or nan, and a reader is told why the number
// is missing.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace swf::eval {

using Json = nlohmann::ordered_json;

// object[key] = value; when not finite: null plus "<key>_reason": `reason` (or a generic one).
void SetNumber(Json* object, const std::string& key, double value, const std::string& reason = "");
// object[key] = null plus "<key>_reason": why the value does not exist.
void SetNull(Json* object, const std::string& key, const std::string& reason);
// SetNumber for each (key, value), in order.
void SetNumbers(Json* object, const std::vector<std::pair<std::string, double>>& fields);
// The values as an array, null where not finite (a gap in a series).
Json Numbers(const std::vector<double>& values);

}  // namespace swf::eval
