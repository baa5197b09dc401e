#pragma once
// The audit of peelcd bench's peer rows (`peelcd bench --audit`): FCL 0.7, Embree 3 and Bullet 3
// each set up as a plain user writes it from the library's own documentation alone, each in a
// file of its own that shares no setup code with the bench's rows (bench/plain_fcl.cpp,
// plain_embree.cpp, plain_bullet.cpp say the setups). One thread; self pairs in the Embree setup
// only (Bullet's collision world and FCL's manager pair distinct objects). Labelled variant
// rows: never the "best" peer.
#include "peelcd/bench/peers.h"

#include <memory>
#include <string>

namespace peelcd::bench {

class PlainPeer : public Peer {
 public:
  enum class Library { fcl, embree, bullet };
  explicit PlainPeer(Library library);
  ~PlainPeer() override;
  PlainPeer(const PlainPeer&) = delete;
  PlainPeer& operator=(const PlainPeer&) = delete;
  std::string name() const override;
  std::string column() const override;
  std::string library() const override;
  bool variant() const override { return true; }
  PeerFrame frame(const std::vector<Object>& objects) override;
  std::string setup() const override;
  std::size_t builds() const override;
  std::size_t refits() const override;

  // One library's setup (bench/plain_<library>.cpp): its frame, its words, its counts.
  struct Impl {
    virtual ~Impl() = default;
    virtual PeerFrame frame(const std::vector<Object>& objects) = 0;
    virtual std::string setup() const = 0;
    std::size_t builds = 0, refits = 0;
  };

 private:
  Library library_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::bench
