#include "apps/camera_json.h"

#include <cmath>
#include <fstream>

#include "common/error.h"

namespace pms::app {
namespace {

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail(path, std::string("not valid JSON: ") + e.what());
  }
}

void read_vector(const nlohmann::json& value, const char* key, float out[3], const std::string& where) {
  const auto it = value.find(key);
  if (it == value.end()) fail(where, std::string("missing \"") + key + "\"");
  if (!it->is_array() || it->size() != 3) fail(where, std::string("\"") + key + "\" must be an array of 3 numbers");
  for (int i = 0; i < 3; ++i) {
    if (!(*it)[i].is_number()) fail(where, std::string("\"") + key + "\" must be an array of 3 numbers");
    out[i] = (*it)[i].get<float>();
    if (!std::isfinite(out[i])) fail(where, std::string("\"") + key + "\" must be finite");
  }
}

uint32_t read_size(const nlohmann::json& value, const char* key, uint32_t fallback, const std::string& where) {
  const auto it = value.find(key);
  if (it == value.end()) return fallback;
  if (!it->is_number_integer() || it->get<int64_t>() < 1 || it->get<int64_t>() > 16384)
    fail(where, std::string("\"") + key + "\" must be an integer in [1, 16384]");
  return uint32_t(it->get<int64_t>());
}

}  // namespace

Camera camera_from_json(const nlohmann::json& value, const std::string& where) {
  if (!value.is_object()) fail(where, "a camera must be a JSON object");
  Camera camera;
  read_vector(value, "eye", camera.eye, where);
  read_vector(value, "target", camera.target, where);
  if (value.contains("up")) read_vector(value, "up", camera.up, where);
  if (value.contains("fovy_deg")) {
    if (!value["fovy_deg"].is_number()) fail(where, "\"fovy_deg\" must be a number");
    camera.fovy_deg = value["fovy_deg"].get<float>();
    if (!(camera.fovy_deg > 0 && camera.fovy_deg < 180)) fail(where, "\"fovy_deg\" must be in (0, 180)");
  }
  camera.width = read_size(value, "width", camera.width, where);
  camera.height = read_size(value, "height", camera.height, where);
  return camera;
}

nlohmann::json camera_to_json(const Camera& camera) {
  auto vec = [](const float v[3]) { return nlohmann::json::array({v[0], v[1], v[2]}); };
  return {{"eye", vec(camera.eye)},      {"target", vec(camera.target)}, {"up", vec(camera.up)},
          {"fovy_deg", camera.fovy_deg}, {"width", camera.width},        {"height", camera.height}};
}

Camera load_camera(const std::string& path) { return camera_from_json(read_json(path), path); }

std::vector<Camera> load_path(const std::string& path) {
  const nlohmann::json value = read_json(path);
  if (!value.is_object() || !value.contains("frames") || !value["frames"].is_array())
    fail(path, "a path must be an object with a \"frames\" array");
  std::vector<Camera> frames;
  for (size_t i = 0; i < value["frames"].size(); ++i)
    frames.push_back(camera_from_json(value["frames"][i], path + ": frame " + std::to_string(i)));
  if (frames.empty()) fail(path, "the path has no frames");
  return frames;
}

void save_path(const std::string& path, const std::vector<Camera>& frames) {
  nlohmann::json out = {{"frames", nlohmann::json::array()}};
  for (const Camera& camera : frames) out["frames"].push_back(camera_to_json(camera));
  std::ofstream file(path);
  if (!file) fail(path, "cannot write file");
  file << out.dump(1) << "\n";
  if (!file) fail(path, "write failed");
}

}  // namespace pms::app
