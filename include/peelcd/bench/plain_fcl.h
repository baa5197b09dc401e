#pragma once
// The audit of peelcd bench's FCL rows (`peelcd bench --audit`): FCL 0.7 as a plain user sets it
// up from its documentation and tests alone, in a file of its own that shares no setup code with
// FclPeer (bench/plain_fcl.cpp says the setup): OBBRSS models, FCL's dynamic AABB tree manager,
// fcl::collide on each of its pairs with every contact asked for. One thread; no self pairs. A
// labelled variant row: never the "best" peer.
#include "peelcd/bench/peers.h"

#include <memory>
#include <string>

namespace peelcd::bench {

class PlainFcl : public Peer {
 public:
  PlainFcl();
  ~PlainFcl() override;
  PlainFcl(const PlainFcl&) = delete;
  PlainFcl& operator=(const PlainFcl&) = delete;
  std::string name() const override;
  std::string column() const override;
  std::string library() const override { return "FCL"; }
  bool variant() const override { return true; }
  PeerFrame frame(const std::vector<Object>& objects) override;
  std::string setup() const override;
  std::size_t builds() const override;
  std::size_t refits() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::bench
