#include "json.hpp"

#include <cmath>

namespace swf::eval {

void SetNumber(Json* object, const std::string& key, double value, const std::string& reason) {
  if (std::isfinite(value)) {
    (*object)[key] = value;
    return;
  }
  SetNull(object, key,
          reason.empty()
              ? "the value is not finite (" + std::string(std::isnan(value) ? "nan" : "inf") + ")"
              : reason);
}

void SetNull(Json* object, const std::string& key, const std::string& reason) {
  (*object)[key] = nullptr;
  (*object)[key + "_reason"] = reason;
}

void SetNumbers(Json* object, const std::vector<std::pair<std::string, double>>& fields) {
  for (const auto& [key, value] : fields) SetNumber(object, key, value);
}

Json Numbers(const std::vector<double>& values) {
  Json array = Json::array();
  for (const double v : values) array.push_back(std::isfinite(v) ? Json(v) : Json(nullptr));
  return array;
}

}  // namespace swf::eval
