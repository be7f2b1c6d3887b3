#include "geojcbb_host/session.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>
#include <utility>

namespace geojcbb::host {

namespace {
std::string hex(std::uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "%08x", v);
  return b;
}
constexpr int kReconnectionsPerRequest = 3;
}  // namespace

LinkSession::LinkSession(SessionOptions o) : o_(std::move(o)) {
  if (!o_.open) throw std::invalid_argument("LinkSession: no way to open the port");
  connect("no device answered");
}

void LinkSession::connect(const char* failure) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(o_.reconnect_ms);
  int backoff_ms = 50;
  std::string last;
  for (;;) {
    try {
      port_.reset();  // close first: a serial port may be opened once at a time
      port_ = o_.open();
      if (!client_) {
        client_ = std::make_unique<LinkClient>(*port_, o_.timeout_ms);
      } else {
        client_->attach(*port_);
      }
      client_->hello(1);
      return;
    } catch (const LinkError& e) {
      if (e.kind == LinkError::Kind::kDevice) throw;  // refused (version, schema): no retry helps
      last = e.what();
    } catch (const std::exception& e) {
      last = e.what();
    }
    if (std::chrono::steady_clock::now() + std::chrono::milliseconds(backoff_ms) >= deadline) {
      throw LinkError(std::string(failure) + " within " + std::to_string(o_.reconnect_ms) + " ms: " + last);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(backoff_ms));
    backoff_ms = std::min(2 * backoff_ms, 1000);
  }
}

LinkSession::~LinkSession() = default;

void LinkSession::say(const std::string& s) const {
  if (o_.note) {
    o_.note(s);
  } else {
    std::printf("  %s\n", s.c_str());
    std::fflush(stdout);
  }
}

bool LinkSession::reconnect(const std::string& why) {
  say("link: " + why + "; reconnecting");
  ++reconnections_;
  const std::uint32_t before = client_->boot_id();
  connect("could not reconnect");
  const std::uint32_t now = client_->boot_id();
  if (now != before) {
    say("the device restarted (boot id " + hex(before) + " -> " + hex(now) + "): its state is gone");
    return false;
  }
  say("reconnected to the same device (boot id " + hex(now) + ")");
  return true;
}

void LinkSession::restart(const std::string& why) {
  ++restarts_;
  ++restarts_in_run_;
  if (restarts_in_run_ > o_.max_restarts) {
    throw LinkError("giving up: " + why + ", and this run was started again " + std::to_string(o_.max_restarts) +
                    " times already (--max-restarts)");
  }
  say(why + ": the run starts again from the beginning (restart " + std::to_string(restarts_in_run_) + " of at most " +
      std::to_string(o_.max_restarts) + ")");
  throw LinkError(why, LinkError::Kind::kRestart);
}

template <class Op>
auto LinkSession::guarded(const char* what, bool in_run, Op&& op) -> decltype(op()) {
  bool resend = false, lost = false;
  for (int attempt = 0;; ++attempt) {
    std::string why;
    bool not_ready = false;
    try {
      if (resend) client_->resend_pending();
      resend = false;
      return op();
    } catch (const LinkError& e) {
      // A reply missing (its frame damaged or dropped on the way, e.g. the ASSOC_RESULT before its
      // POSE) may be the last batch's, which the device sends again when the batch is resent: so
      // reconnect and resend once. Missing again, it is gone for good.
      if (e.kind == LinkError::Kind::kLost && (!in_run || lost)) {
        if (in_run) restart(e.what());
        throw;
      }
      lost = lost || e.kind == LinkError::Kind::kLost;
      if (e.kind != LinkError::Kind::kTimeout && e.kind != LinkError::Kind::kNotReady &&
          e.kind != LinkError::Kind::kLost)
        throw;
      not_ready = e.kind == LinkError::Kind::kNotReady;
      why = e.what();
    } catch (const std::runtime_error& e) {  // the transport: the port closed or failed
      why = e.what();
    }
    if (attempt >= kReconnectionsPerRequest) {
      throw LinkError(std::string(what) + " failed after " + std::to_string(kReconnectionsPerRequest) +
                      " reconnections: " + why);
    }
    const bool kept = reconnect(why);
    if (in_run && !kept) restart("the device restarted");
    if (in_run && not_ready) restart("the device has no session (ERROR not-ready)");
    resend = kept;
  }
}

void LinkSession::configure(const proto::Config& c) {
  guarded("CONFIG", true, [&] { client_->configure(c); });
}

void LinkSession::reset(const proto::Reset& r) {
  guarded("RESET", true, [&] { client_->reset(r); });
}

// A stream frame is kept by the client before it is written: after a reconnection the resend
// delivers it, so the send itself is not repeated (that would be a new frame, applied twice).
void LinkSession::odometry(const proto::Odometry& o) {
  bool sent = false;
  guarded("ODOMETRY", true, [&] {
    if (!sent) {
      sent = true;
      client_->odometry(o);
    }
  });
}

void LinkSession::odom_delta(const proto::OdomDelta& d) {
  bool sent = false;
  guarded("ODOM_DELTA", true, [&] {
    if (!sent) {
      sent = true;
      client_->odom_delta(d);
    }
  });
}

void LinkSession::relocalise(const proto::Relocalise& r) {
  bool sent = false;
  guarded("RELOCALISE", true, [&] {
    if (!sent) {
      sent = true;
      client_->relocalise(r);
    }
  });
}

void LinkSession::send_scan(const LinkObsBatch& b) {
  bool sent = false;
  guarded("OBS_BATCH", true, [&] {
    if (!sent) {
      sent = true;
      client_->send_scan(b);
    }
  });
}

LinkClient::ScanReply LinkSession::receive_scan(std::uint32_t batch_id) {
  return guarded("the reply to a batch", true, [&] { return client_->receive_scan(batch_id); });
}

void LinkSession::send_seed(const proto::SubmapSeed& s) {
  bool sent = false;
  guarded("SUBMAP_SEED", true, [&] {
    if (!sent) {
      sent = true;
      client_->send_seed(s);
    }
  });
}

LinkAssocResult LinkSession::receive_seed(std::uint32_t batch_id) {
  return guarded("the answer to a seed", true, [&] { return client_->receive_seed(batch_id); });
}

// After a reconnection to the same device the map is still pending there: it is asked for again.
LinkClient::WireSubmap LinkSession::receive_submap(std::uint32_t map_id) {
  bool first = true;
  return guarded("the frames of a local map", true, [&] {
    if (!first) client_->request_submap(map_id);
    first = false;
    return client_->receive_submap(map_id);
  });
}

void LinkSession::request_submap(std::uint32_t map_id) {
  guarded("SUBMAP_ACK", true, [&] { client_->request_submap(map_id); });
}

void LinkSession::submap_received(std::uint32_t map_id) {
  guarded("SUBMAP_ACK", true, [&] { client_->submap_received(map_id); });
}

proto::Stats LinkSession::stats() {
  return guarded("STATS", false, [&] { return client_->stats(); });
}

void LinkSession::ping(std::uint32_t nonce) {
  guarded("PING", false, [&] { client_->ping(nonce); });
}

}  // namespace geojcbb::host
