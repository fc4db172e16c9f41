#include "client/load_client.h"

#include <optional>

#include "client/link.h"
#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "spm/hierarchy.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::client {

// 64 MiB of frames may wait unread: a client that falls behind back-pressures the server instead of
// dropping anything.
constexpr size_t kMaxQueuedBytes = size_t(64) << 20;

LoadClient::LoadClient(std::string host, uint16_t port, std::string model_name, LoadClientOptions options)
    : host_(std::move(host)), model_name_(std::move(model_name)), port_(port), options_(options) {
  if (options_.model) held_ = std::make_unique<HeldLeaves>(*options_.model);
}

LoadClient::~LoadClient() = default;

void LoadClient::open(bool resume) {
  drop();
  server_ = std::make_unique<ServerConnection>(std::make_unique<Link>(host_, port_, kMaxQueuedBytes), "pmstream-bench",
                                               options_.answer_timeout);
  protocol::Open open{model_name_, {}};
  if (resume && holds_splits()) {
    open.resume = held_->leaves();
  } else if (held_) {
    held_->hold_roots();
  }
  const protocol::Base base = server_->open(open);
  context_ = protocol::stream_context(base);
  if (!protocol::carries_split_records(open.mode)) return;
  context_.records = server_->next_codec(context_).codec;
  if (open.resume.empty() || !hierarchy_) start_hierarchy(base);  // a resumed session keeps the one held
  context_.held = protocol::held_in(*hierarchy_, context_.grid);
}

void LoadClient::start_hierarchy(const protocol::Base& base) {
  // The records are coded against v_s's normal and color too: the hierarchy keeps what the model has.
  hierarchy_ = std::make_unique<VertexHierarchy>(base.has_normals, base.has_colors);
  for (uint32_t r = 0; r < base.root_count(); ++r)
    hierarchy_->add_root(VertexId{r, 1}, &base.positions[3 * size_t(r)], base.refine[r],
                         base.has_normals ? &base.normals[3 * size_t(r)] : nullptr,
                         base.has_colors ? &base.colors[4 * size_t(r)] : nullptr);
}

double LoadClient::view(const Camera& camera, float tolerance) {
  const uint32_t frame = ++frame_;
  const auto sent = std::chrono::steady_clock::now();
  server_->send_view(camera, tolerance, frame);
  for (;;) {
    const protocol::VSplits batch = server_->next_batch(context_);
    splits_received_ += batch.splits.size();
    if (context_.records)
      for (const SplitRecord& split : batch.splits) hierarchy_->add_split(split);
    if (held_)
      for (const SplitRecord& split : batch.splits) held_->split(split.vs);
    if (batch.final && batch.frame == frame) break;
  }
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - sent).count();
}

void LoadClient::drop() { server_.reset(); }

}  // namespace pms::client
