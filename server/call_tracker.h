// Counts the calls in flight on the server (every service: ours, health,
// reflection), so that shutdown can tell "a client is still being served"
// from "only idle connections are left". gRPC's graceful shutdown waits for
// every connection to answer its final GOAWAY ping; an idle client that does
// not read its socket (measured: Python grpcio between calls) held the
// shutdown for the whole grace period with no call open. Once no call is in
// flight, server_main closes such connections at once.
#pragma once

#include <grpcpp/support/server_interceptor.h>

#include <atomic>
#include <memory>

namespace gdvr::server {

class CallTracker {
 public:
  int active() const { return active_.load(); }
  // Installed with ServerBuilder::experimental().SetInterceptorCreators:
  // gRPC creates one interceptor per call and deletes it when the call ends.
  std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> interceptor_factory();

 private:
  friend class CallCountingInterceptor;
  std::atomic<int> active_{0};
};

}  // namespace gdvr::server
