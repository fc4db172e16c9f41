// Scripted camera paths over a model (`pmstream path`): orbit, scan (zheng-chan 2006 §6's first route: close
// to the surface, bottom to top), zoom (far to a close-up), look (kim-lee-kobbelt 2005 Fig. 5: around the model
// from top to bottom) and rotate (zheng-chan §6's second route: in close, circling faster and faster).
// Deterministic: the same model and options give the
// same cameras, bit for bit.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/camera.h"
#include "spm/hierarchy.h"

namespace pms::app {

enum class PathKind { orbit, scan, zoom, look, rotate };

// "orbit" | "scan" | "zoom" | "look" | "rotate"; pms::Error otherwise.
PathKind parse_path_kind(const std::string& name);

struct PathOptions {
  uint32_t frames = 180;
  float fovy_deg = 45;
  uint32_t width = 800, height = 600;
};

// Up is the axis of the bounding box's smallest extent when the model is flat (under half its middle
// extent: a terrain), else +y (the scans' convention). Orbit: a full circle around the box centre, 20°
// above the horizontal plane, at the distance where the bounding sphere just fits the narrower field of
// view. Scan: facing the model from one side at a distance that shows a third of its height, looking
// horizontally at the vertical axis through the centre, rising from the bottom of the box to the top
// while swinging 60° around it. Zoom: toward the model's most extreme surface vertex in the viewing
// direction, from 6 framing distances (the model small on screen) to 2% of the box diagonal, geometric in
// distance so the speed feels constant. Look: the orbit's circle at its distance, its elevation falling from
// 60° above the horizontal plane to 60° below over the turn, so a lap sees the top, the sides and the
// bottom (kim-lee-kobbelt fly it twice: E3/E4's two laps). Rotate (zheng-chan 2006 §6's second route, 194
// frames there): in from the orbit's distance to the scan's over the first third while circling the vertical
// axis 10° above the horizontal plane, faster and faster (the angle grows with the square of time): two
// turns. pms::Error for no frames or bad camera settings.
std::vector<Camera> make_camera_path(PathKind kind, const ModelData& model, const PathOptions& options);

}  // namespace pms::app
