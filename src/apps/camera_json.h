// CAM.json and PATH.json (docs/cli.md, "CAM.json and PATH.json", contract):
//   CAM  = {"eye":[x,y,z],"target":[x,y,z],"up":[x,y,z],"fovy_deg":f,"width":w,"height":h}
//   PATH = {"frames":[CAM, ...]}
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/camera.h"

namespace pms::app {

// Throw pms::Error naming the file and the field for a missing file, bad JSON or a bad value.
Camera load_camera(const std::string& path);
std::vector<Camera> load_path(const std::string& path);

Camera camera_from_json(const nlohmann::json& value, const std::string& where);
nlohmann::json camera_to_json(const Camera& camera);
void save_path(const std::string& path, const std::vector<Camera>& frames);

}  // namespace pms::app
