#include "plain_setups.h"

namespace peelcd::bench {

PlainPeer::PlainPeer(Library library)
    : library_(library),
      impl_(library == Library::fcl ? plain_fcl() : library == Library::embree ? plain_embree() : plain_bullet()) {}
PlainPeer::~PlainPeer() = default;

std::string PlainPeer::library() const {
  return library_ == Library::fcl ? "FCL" : library_ == Library::embree ? "Embree" : "Bullet";
}
std::string PlainPeer::name() const {
  return library_ == Library::fcl      ? "FCL 0.7, plain setup (audit)"
         : library_ == Library::embree ? "Embree 3 rtcCollide, plain setup (audit)"
                                       : "Bullet 3 GImpact, plain setup (audit)";
}
std::string PlainPeer::column() const { return library() + " pl"; }
PeerFrame PlainPeer::frame(const std::vector<Object>& objects) { return impl_->frame(objects); }
std::string PlainPeer::setup() const { return impl_->setup(); }
std::size_t PlainPeer::builds() const { return impl_->builds; }
std::size_t PlainPeer::refits() const { return impl_->refits; }

}  // namespace peelcd::bench
