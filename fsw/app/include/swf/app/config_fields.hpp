// The building blocks of configuration keys: typed setters that parse a value or say why not, and
// the wording of every refusal ("<where>: <field>: <problem>"). The flight process's own keys
// (config.cpp) and the keys a program built on it adds (ConfigExtension: tools/sil's sim.*) are
// made of the same blocks, so a simulator key is refused in the same words as a flight key.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace swf::app {

struct FswConfig;  // config.hpp

// A field's setter: parses the text value into the configuration or writes why not.
using ConfigSetter = std::function<bool(const std::string& value, FswConfig* c, std::string* why)>;

// At most a bounded, printable excerpt of what was read (bytes outside printable ASCII as \xNN):
// an error never repeats megabytes or writes terminal control sequences.
std::string Excerpt(const std::string& s);
// The value in quotes, excerpted.
std::string Quoted(const std::string& v);
bool ParseDouble(const std::string& v, double* out, std::string* why);
bool ParseInt(const std::string& v, std::int64_t* out, std::string* why);
// "[lo, hi]", with "(" when the low end is excluded; and the test it names.
std::string Interval(double lo, double hi, bool lo_open);
bool InInterval(double d, double lo, double hi, bool lo_open);
// `v` with `decimals` digits after the point.
std::string Fixed(double v, int decimals);
// Where an error about `field` points: the line (or --set) that set it; the file when the field
// kept its default (`origin` when the configuration came from no file).
std::string ConfigWhere(const FswConfig& c, const std::string& field, const std::string& origin);
// "<where>: <field>: <why>" into `error`; false.
bool RefuseField(const FswConfig& c, const std::string& field, const std::string& origin,
                 const std::string& why, std::string* error);

// The front end's disparity search, min(max_disparity_px, width / 2), covers f b / range at the
// closest range flown plus one pixel for the sub-pixel fit (`shift_px`: a disparity the right
// image adds at every range). `range_from` and `rig_from` say where range and rig come from.
bool DisparityFits(const FswConfig& c, double fx_px, double baseline_m, int width_px,
                   double range_m, const std::string& range_from, const std::string& rig_from,
                   const std::string& origin, std::string* error, double shift_px = 0.0);

// An integer of type T into *get(c), inside [lo, hi]; `limit_note` says where a compiled limit
// comes from.
template <typename T, typename Get>
ConfigSetter Int(Get get, std::int64_t lo, std::int64_t hi, const char* limit_note = "") {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    std::int64_t i = 0;
    if (!ParseInt(v, &i, why)) return false;
    if (i < lo || i > hi) {
      *why = Excerpt(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]" +
             limit_note;
      return false;
    }
    *get(c) = static_cast<T>(i);
    return true;
  };
}

// A finite number into *get(c), inside [lo, hi] (or (lo, hi]).
template <typename Get>
ConfigSetter Number(Get get, double lo, double hi, bool lo_open = false) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    double d = 0.0;
    if (!ParseDouble(v, &d, why)) return false;
    if (!InInterval(d, lo, hi, lo_open)) {
      *why = Excerpt(v) + " is outside " + Interval(lo, hi, lo_open);
      return false;
    }
    *get(c) = d;
    return true;
  };
}

template <typename Get>
ConfigSetter Bool(Get get) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    if (v == "true" || v == "yes" || v == "1") {
      *get(c) = true;
    } else if (v == "false" || v == "no" || v == "0") {
      *get(c) = false;
    } else {
      *why = Quoted(v) + " is not true/false";
      return false;
    }
    return true;
  };
}

template <typename Get>
ConfigSetter Text(Get get) {
  return [=](const std::string& v, FswConfig* c, std::string*) {
    *get(c) = v;
    return true;
  };
}

// One of the texts `named` pairs with a value: that value into *get(c). The refusal lists the
// texts in their order.
template <typename T, typename Get>
ConfigSetter OneOf(Get get, std::vector<std::pair<std::string, T>> named) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    for (const auto& [text, value] : named) {
      if (v == text) {
        *get(c) = value;
        return true;
      }
    }
    *why = Quoted(v) + " is not one of";
    for (const auto& n : named) *why += " " + n.first;
    return false;
  };
}

// One of the texts in `allowed`, kept as text.
template <typename Get>
ConfigSetter OneOf(Get get, std::initializer_list<const char*> allowed) {
  std::vector<std::pair<std::string, std::string>> named;
  for (const char* a : allowed) named.emplace_back(a, a);
  return OneOf<std::string>(get, std::move(named));
}

// N finite numbers ("a b c" or "a, b, c") into get(c)[0..N), each inside [lo, hi]; `names` says
// what they are ("x y z").
template <int N, typename Get>
ConfigSetter Numbers(Get get, double lo, double hi, const char* names) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    std::string spaced = v;
    for (char& ch : spaced) ch = ch == ',' ? ' ' : ch;
    std::istringstream in(spaced);
    double p[N];
    std::string rest;
    for (double& x : p) {
      if (!(in >> x) || !std::isfinite(x)) {
        *why = Quoted(v) + " is not " + std::to_string(N) + " finite numbers (" + names + ")";
        return false;
      }
    }
    if (in >> rest) {
      *why = Quoted(v) + " is not " + std::to_string(N) + " finite numbers (" + names + ")";
      return false;
    }
    for (const double x : p) {
      if (!InInterval(x, lo, hi, false)) {
        std::ostringstream o;
        o << Excerpt(v) << ": " << x << " is outside " << Interval(lo, hi, false);
        *why = o.str();
        return false;
      }
    }
    for (int i = 0; i < N; ++i) get(c)[i] = p[i];
    return true;
  };
}

}  // namespace swf::app
