#include "bench/tier_flight.h"

#include <exception>
#include <thread>

#include "bench/on_threads.h"

namespace pms::bench {
namespace {

void fly_one(const TierPlan& plan, size_t index, TierViewer& out,
             const std::function<void(size_t, client::ReceiverClient&)>& at_end) {
  const TierViewerPlan& viewer = plan.viewers[index];
  std::this_thread::sleep_for(viewer.start);
  try {
    client::ReceiverOptions options;
    options.tolerance = plan.tolerance;
    options.fetch = viewer.fetch;
    options.http.local_address = viewer.local_address;
    client::ReceiverClient client(plan.server, options);
    client.open(plan.model);
    for (size_t frame = 0; frame < viewer.path.size(); ++frame) {
      if (index == plan.event_viewer && frame == plan.event_frame && plan.event) plan.event();
      client.frame(viewer.path[frame]);
      ++out.frames;
    }
    out.splits = client.session().splits_received();
    out.totals = client.totals();
    out.counters = client.counters();
    if (at_end) at_end(index, client);
  } catch (const std::exception& e) {
    out.error = e.what();
  }
}

}  // namespace

std::vector<TierViewer> fly_tier(const TierPlan& plan,
                                 const std::function<void(size_t, client::ReceiverClient&)>& at_end) {
  std::vector<TierViewer> viewers(plan.viewers.size());
  on_threads(plan.viewers.size(), [&](size_t i) { fly_one(plan, i, viewers[i], at_end); });
  return viewers;
}

}  // namespace pms::bench
