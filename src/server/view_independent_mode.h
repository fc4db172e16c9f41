// The view-independent mode, the baseline of kim-lee-kobbelt 2005 §8 (Fig. 9): the server streams the plain
// PM order, coarse to fine, in packets without refinement info; each VIEW extends the prefix of split_order
// sent up to the shortest one whose front satisfies the view. The client applies every split as it comes
// and never evaluates qrefine.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>

#include "protocol/client_messages.h"
#include "protocol/stream_context.h"
#include "server/active_tags.h"
#include "server/selective_streaming.h"
#include "server/session_mode.h"

namespace pms::server {

class ViewIndependentMode : public SessionMode {
 public:
  // Queues BASE at once (this mode cannot resume: OPEN with a front is bad_message).
  ViewIndependentMode(const protocol::OpenHeader& open, const ModeContext& context);
  ~ViewIndependentMode() override;

  void receive(const protocol::ClientMessage& message) override;
  bool has_work() const override { return view_.pending; }
  void pump(uint64_t& work) override;
  bool opened() const override { return true; }
  void stop() override;
  size_t state_bytes() const override;
  size_t front_bytes() const override { return tags_.memory_bytes(); }
  uint64_t splits_sent() const override { return sent_; }
  ActiveTags front_tags() const override { return tags_; }

 private:
  struct Prefix;  // the prefix a VIEW needs, found a slice at a time
  void walk(Prefix& p, uint64_t& work);
  void advance(Prefix& p, uint64_t& work);
  void stream(Prefix& p, uint64_t& work);

  ModeContext context_;
  protocol::StreamContext wire_;  // the model's, without refinement info
  ActiveTags tags_;               // the front of split_order[0, sent_)
  LatestView view_;
  Importance importance_;
  std::unique_ptr<Prefix> prefix_;
  uint64_t sent_ = 0;  // split_order[0, sent_) sent
};

}  // namespace pms::server
