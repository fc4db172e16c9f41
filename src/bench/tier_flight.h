// Receiver-driven viewers (client::ReceiverClient, lock-step frames) flying their own paths through one
// cache tier (nginx in front of origins), each from a client address of its own, while one event (the
// test or the bench kills an origin) happens mid-flight. What the tier test and the bench's tier figure
// fly, so both measure the same thing.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "client/receiver_client.h"
#include "common/camera.h"

namespace pms::bench {

struct TierViewerPlan {
  std::vector<Camera> path;
  client::FetchPolicy fetch = client::FetchPolicy::blocks;
  std::string local_address;          // the viewer's own address on loopback ("127.0.0.7"); empty: any
  std::chrono::milliseconds start{0};  // after the flight begins
};

struct TierPlan {
  client::HttpUrl server;  // the cache tier
  std::string model;
  float tolerance = 1;
  std::vector<TierViewerPlan> viewers;
  // Viewer `event_viewer` runs `event` (empty: none) before frame `event_frame` of its path; the others fly
  // on, so it may cut answers in the middle.
  size_t event_viewer = 0, event_frame = SIZE_MAX;
  std::function<void()> event;
};

struct TierViewer {
  std::string error;  // empty: the viewer flew its whole path
  uint64_t frames = 0, splits = 0;
  client::ReceiverTotals totals;   // split GETs and the cache's HITs among them
  client::HttpCounters counters;   // every GET, bytes on the wire and payload
};

// Flies every viewer in a thread of its own; `at_end` (if set) runs on each viewer that finished, on its
// thread, with its client (its mesh at the last camera).
std::vector<TierViewer> fly_tier(const TierPlan& plan,
                                 const std::function<void(size_t viewer, client::ReceiverClient&)>& at_end = {});

}  // namespace pms::bench
