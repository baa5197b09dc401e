#pragma once
// The audit of peelcd bench's Bullet row (`peelcd bench --audit`): Bullet 3's GImpact as a plain
// user sets it up from Bullet's documentation and demos alone, in a file of its own that shares
// no setup code with BulletPeer (bench/plain_bullet.cpp says the setup): a btCollisionWorld, its
// broad phase, GImpact's own collision algorithm and triangle test, the triangle pairs taken
// from the contact-added callback. One thread; no self pairs. A labelled variant row: never the
// "best" peer.
#include "peelcd/bench/peers.h"

#include <memory>
#include <string>

namespace peelcd::bench {

class PlainBullet : public Peer {
 public:
  PlainBullet();
  ~PlainBullet() override;
  PlainBullet(const PlainBullet&) = delete;
  PlainBullet& operator=(const PlainBullet&) = delete;
  std::string name() const override;
  std::string column() const override;
  std::string library() const override { return "Bullet"; }
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
