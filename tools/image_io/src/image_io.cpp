#include "swf/image_io/image_io.hpp"

#include <stb_image.h>
#include <stb_image_write.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace swf::image_io {

namespace {

bool Load(const std::string& path, GrayImage* image, std::string* error, bool channel0) {
  int w = 0;
  int h = 0;
  int channels = 0;
  stbi_uc* data = stbi_load(path.c_str(), &w, &h, &channels, channel0 ? 0 : 1);
  if (data == nullptr) {
    *error = path + ": " + (stbi_failure_reason() ? stbi_failure_reason() : "unreadable");
    return false;
  }
  image->Resize(w, h);
  const int stride = channel0 ? channels : 1;
  for (std::size_t i = 0; i < image->pixels.size(); ++i) image->pixels[i] = data[i * stride];
  stbi_image_free(data);
  return true;
}

// The numbers of the first [...] list after `key:` (searched from `from`), or empty.
std::vector<double> ListAfter(const std::string& text, const std::string& key,
                              std::size_t from = 0) {
  std::vector<double> values;
  std::size_t k = text.find(key + ":", from);
  while (k != std::string::npos && k > 0 && text[k - 1] != '\n' && text[k - 1] != ' ') {
    k = text.find(key + ":", k + 1);  // only whole keys
  }
  if (k == std::string::npos) return values;
  const std::size_t open = text.find('[', k);
  const std::size_t close = text.find(']', open);
  if (open == std::string::npos || close == std::string::npos) return values;
  std::string body = text.substr(open + 1, close - open - 1);
  for (char& c : body) {
    if (c == ',' || c == '\n' || c == '\r') c = ' ';
  }
  std::istringstream in(body);
  double v = 0.0;
  while (in >> v) values.push_back(v);
  return values;
}

bool ScalarAfter(const std::string& text, const std::string& key, double* value) {
  const std::size_t k = text.find(key + ":");
  if (k == std::string::npos) return false;
  return std::sscanf(text.c_str() + k + key.size() + 1, "%lf", value) == 1;
}

}  // namespace

bool LoadGray(const std::string& path, GrayImage* image, std::string* error) {
  return Load(path, image, error, false);
}

bool LoadChannel0(const std::string& path, GrayImage* image, std::string* error) {
  return Load(path, image, error, true);
}

bool SavePng(const std::string& path, const RgbImage& image, std::string* error) {
  if (stbi_write_png(path.c_str(), image.width, image.height, 3, image.pixels.data(),
                     image.width * 3) == 0) {
    *error = path + ": cannot write PNG";
    return false;
  }
  return true;
}

bool FlowField::Known(int x, int y) const {
  const float u = U(x, y);
  const float v = V(x, y);
  return std::isfinite(u) && std::isfinite(v) && std::fabs(u) < 1e9f && std::fabs(v) < 1e9f;
}

bool LoadFlo(const std::string& path, FlowField* flow, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  float magic = 0.0f;
  std::int32_t w = 0;
  std::int32_t h = 0;
  in.read(reinterpret_cast<char*>(&magic), 4);
  in.read(reinterpret_cast<char*>(&w), 4);
  in.read(reinterpret_cast<char*>(&h), 4);
  if (!in || magic != 202021.25f || w <= 0 || h <= 0 || w > 100000 || h > 100000) {
    *error = path + ": not a Middlebury .flo file";
    return false;
  }
  flow->width = w;
  flow->height = h;
  flow->uv.resize(2 * static_cast<std::size_t>(w) * h);
  in.read(reinterpret_cast<char*>(flow->uv.data()),
          static_cast<std::streamsize>(flow->uv.size() * sizeof(float)));
  if (!in) {
    *error = path + ": truncated";
    return false;
  }
  return true;
}

bool LoadCalibration(const std::string& path, frontend::CameraCalibration* c, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  *c = frontend::CameraCalibration{};
  std::vector<double> distortion;
  const std::vector<double> intrinsics = ListAfter(text, "intrinsics");
  if (intrinsics.size() == 4) {  // EuRoC / Kalibr
    c->fx = intrinsics[0];
    c->fy = intrinsics[1];
    c->cx = intrinsics[2];
    c->cy = intrinsics[3];
    const std::vector<double> resolution = ListAfter(text, "resolution");
    if (resolution.size() != 2) {
      *error = path + ": resolution [w, h] missing";
      return false;
    }
    c->width = static_cast<int>(resolution[0]);
    c->height = static_cast<int>(resolution[1]);
    distortion = ListAfter(text, "distortion_coefficients");
  } else {  // ROS camera_info / OpenCV
    const std::size_t k = text.find("camera_matrix:");
    const std::vector<double> m =
        k == std::string::npos ? std::vector<double>{} : ListAfter(text, "data", k);
    double w = 0.0;
    double h = 0.0;
    if (m.size() != 9 || !ScalarAfter(text, "image_width", &w) ||
        !ScalarAfter(text, "image_height", &h)) {
      *error = path + ": neither EuRoC intrinsics nor ROS camera_matrix/image_width found";
      return false;
    }
    c->fx = m[0];
    c->cx = m[2];
    c->fy = m[4];
    c->cy = m[5];
    c->width = static_cast<int>(w);
    c->height = static_cast<int>(h);
    const std::size_t d = text.find("distortion_coefficients:");
    if (d != std::string::npos) distortion = ListAfter(text, "data", d);
  }
  if (distortion.size() < 4 || distortion.size() > 5) {
    *error = path + ": need 4 or 5 radial-tangential distortion coefficients";
    return false;
  }
  c->k1 = distortion[0];
  c->k2 = distortion[1];
  c->p1 = distortion[2];
  c->p2 = distortion[3];
  c->k3 = distortion.size() == 5 ? distortion[4] : 0.0;
  const std::size_t t = text.find("T_BS:");
  if (t != std::string::npos) {
    const std::vector<double> m = ListAfter(text, "data", t);
    if (m.size() != 16) {
      *error = path + ": T_BS must hold 16 numbers";
      return false;
    }
    Eigen::Matrix4d mat;
    for (int i = 0; i < 16; ++i) mat(i / 4, i % 4) = m[i];
    c->body_T_camera = estimator::Pose<double>::FromMatrix(mat);
  }
  if (!(c->fx > 0.0 && c->fy > 0.0 && c->width > 0 && c->height > 0)) {
    *error = path + ": invalid intrinsics or size";
    return false;
  }
  return true;
}

}  // namespace swf::image_io
