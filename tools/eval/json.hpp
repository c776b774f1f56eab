// JSON output of swf-eval. Every number goes through JsonNumber, so a non-finite value (a
// diverged estimate, a ratio of two zeros) is written as null with a "<key>_reason" string next
// to it instead of the invalid tokens inf/nan; ValidateJson is the strict check the tool runs
// on every file before writing it (and the tests run on what the tool wrote).
#pragma once

#include <string>
#include <vector>

namespace swf::eval {

// A number as JSON: "%.*g" with `digits` significant digits, or "null" when not finite.
std::string JsonNumber(double value, int digits = 6);
// A string as a JSON string literal (quotes, backslashes and control characters escaped).
std::string JsonString(const std::string& text);
// [a, b, ...] with every element through JsonNumber.
std::string JsonArray(const std::vector<double>& values, int digits = 6);

// An object built field by field in insertion order.
class JsonObject {
 public:
  // A number; when not finite: null plus "<key>_reason": `reason` (or a generic one).
  JsonObject& Number(const std::string& key, double value, const std::string& reason = "",
                     int digits = 6);
  // null plus "<key>_reason": why the value does not exist.
  JsonObject& Null(const std::string& key, const std::string& reason);
  JsonObject& Integer(const std::string& key, long long value);
  JsonObject& String(const std::string& key, const std::string& value);
  JsonObject& Bool(const std::string& key, bool value);
  // Already-formatted JSON (a nested object or array).
  JsonObject& Raw(const std::string& key, const std::string& json);
  // The object; `indent` spaces before each field, one field per line.
  std::string Text(int indent = 2) const;

 private:
  std::vector<std::string> fields_;  // "\"key\": value"
};

// Strict RFC 8259 check (no inf/nan/trailing commas/comments). On failure *error names the byte
// offset and what was expected there.
bool ValidateJson(const std::string& text, std::string* error);

// Validates, then writes `text` to `path`; false with *error naming the path and the reason.
bool WriteJsonFile(const std::string& path, const std::string& text, std::string* error);

}  // namespace swf::eval
