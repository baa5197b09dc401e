#pragma once
// The audit of peelcd bench's Embree rows (`peelcd bench --audit`): Embree 3's rtcCollide as a
// plain user writes it from Embree's API documentation alone, in a file of its own that shares
// no setup code with EmbreePeer (bench/plain_embree.cpp says the setup). One thread; world space;
// no self pairs. A labelled variant row: never the "best" peer.
#include "peelcd/bench/peers.h"

#include <memory>
#include <string>

namespace peelcd::bench {

class PlainEmbree : public Peer {
 public:
  PlainEmbree();
  ~PlainEmbree() override;
  PlainEmbree(const PlainEmbree&) = delete;
  PlainEmbree& operator=(const PlainEmbree&) = delete;
  std::string name() const override;
  std::string column() const override;
  std::string library() const override { return "Embree"; }
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
