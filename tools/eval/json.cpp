#include "json.hpp"

#include "swf/cli/cli.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace swf::eval {

std::string JsonNumber(double value, int digits) {
  if (!std::isfinite(value)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*g", digits, value);
  return buf;
}

std::string JsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", static_cast<unsigned>(c));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string JsonArray(const std::vector<double>& values, int digits) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) {
    out += (i ? ", " : "") + JsonNumber(values[i], digits);
  }
  return out + "]";
}

JsonObject& JsonObject::Number(const std::string& key, double value, const std::string& reason,
                               int digits) {
  if (std::isfinite(value)) return Raw(key, JsonNumber(value, digits));
  return Null(key, reason.empty() ? "the value is not finite (" +
                                        std::string(std::isnan(value) ? "nan" : "inf") + ")"
                                  : reason);
}

JsonObject& JsonObject::Null(const std::string& key, const std::string& reason) {
  Raw(key, "null");
  return Raw(key + "_reason", JsonString(reason));
}

JsonObject& JsonObject::Integer(const std::string& key, long long value) {
  return Raw(key, std::to_string(value));
}

JsonObject& JsonObject::String(const std::string& key, const std::string& value) {
  return Raw(key, JsonString(value));
}

JsonObject& JsonObject::Bool(const std::string& key, bool value) {
  return Raw(key, value ? "true" : "false");
}

JsonObject& JsonObject::Raw(const std::string& key, const std::string& json) {
  fields_.push_back(JsonString(key) + ": " + json);
  return *this;
}

std::string JsonObject::Text(int indent) const {
  if (fields_.empty()) return "{}";
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  const std::string close_pad(static_cast<std::size_t>(indent >= 2 ? indent - 2 : 0), ' ');
  std::string out = "{\n";
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    out += pad + fields_[i] + (i + 1 < fields_.size() ? ",\n" : "\n");
  }
  return out + close_pad + "}";
}

namespace {

// Recursive-descent recogniser of one JSON value; depth-limited so a hostile file cannot
// exhaust the stack.
class Checker {
 public:
  explicit Checker(const std::string& text) : s_(text) {}

  bool Document(std::string* error) {
    Space();
    if (!Value(0)) return Fail(error);
    Space();
    if (i_ != s_.size()) {
      expected_ = "end of text";
      return Fail(error);
    }
    return true;
  }

 private:
  bool Fail(std::string* error) const {
    *error = "invalid JSON at byte " + std::to_string(i_) + ": expected " + expected_;
    return false;
  }
  void Space() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\r' || s_[i_] == '\t'))
      ++i_;
  }
  bool Eat(char c) {
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    expected_ = std::string("'") + c + "'";
    return false;
  }
  bool Literal(const char* word) {
    const std::string w(word);
    if (s_.compare(i_, w.size(), w) != 0) {
      expected_ = "a value";
      return false;
    }
    i_ += w.size();
    return true;
  }
  bool Digits() {
    const std::size_t start = i_;
    while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
    if (i_ == start) expected_ = "a digit";
    return i_ > start;
  }
  bool Number() {
    if (i_ < s_.size() && s_[i_] == '-') ++i_;
    if (i_ < s_.size() && s_[i_] == '0') {
      ++i_;
    } else if (!Digits()) {
      return false;
    }
    if (i_ < s_.size() && s_[i_] == '.') {
      ++i_;
      if (!Digits()) return false;
    }
    if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
      ++i_;
      if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
      if (!Digits()) return false;
    }
    return true;
  }
  bool String() {
    if (!Eat('"')) return false;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (static_cast<unsigned char>(s_[i_]) < 0x20) {
        expected_ = "no control character inside a string";
        return false;
      }
      if (s_[i_] == '\\') {
        ++i_;
        if (i_ >= s_.size() || std::string("\"\\/bfnrtu").find(s_[i_]) == std::string::npos) {
          expected_ = "an escape character";
          return false;
        }
      }
      ++i_;
    }
    return Eat('"');
  }
  bool Value(int depth) {
    if (depth > 64 || i_ >= s_.size()) {
      expected_ = depth > 64 ? "nesting below 64 levels" : "a value";
      return false;
    }
    const char c = s_[i_];
    if (c == '{') return Container('}', depth, true);
    if (c == '[') return Container(']', depth, false);
    if (c == '"') return String();
    if (c == 't') return Literal("true");
    if (c == 'f') return Literal("false");
    if (c == 'n') return Literal("null");
    if (c == '-' || std::isdigit(static_cast<unsigned char>(c))) return Number();
    expected_ = "a value (inf and nan are not JSON)";
    return false;
  }
  bool Container(char close, int depth, bool object) {
    ++i_;
    Space();
    if (i_ < s_.size() && s_[i_] == close) {
      ++i_;
      return true;
    }
    while (true) {
      Space();
      if (object) {
        if (!String()) return false;
        Space();
        if (!Eat(':')) return false;
        Space();
      }
      if (!Value(depth + 1)) return false;
      Space();
      if (i_ < s_.size() && s_[i_] == ',') {
        ++i_;
        continue;
      }
      return Eat(close);
    }
  }

  const std::string& s_;
  std::size_t i_ = 0;
  std::string expected_ = "a value";
};

}  // namespace

bool ValidateJson(const std::string& text, std::string* error) {
  return Checker(text).Document(error);
}

bool WriteJsonFile(const std::string& path, const std::string& text, std::string* error) {
  std::string why;
  if (!ValidateJson(text, &why)) {
    *error = path + ": not written, " + why;
    return false;
  }
  // Whole or not at all, in a directory created when missing (docs/cli.md).
  return cli::WriteFileAtomically(path, text.empty() || text.back() != '\n' ? text + "\n" : text,
                                  error);
}

}  // namespace swf::eval
