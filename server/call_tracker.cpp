#include "server/call_tracker.h"

namespace gdvr::server {

class CallCountingInterceptor : public grpc::experimental::Interceptor {
 public:
  explicit CallCountingInterceptor(CallTracker* tracker) : tracker_(tracker) { ++tracker_->active_; }
  ~CallCountingInterceptor() override { --tracker_->active_; }
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override { methods->Proceed(); }

 private:
  CallTracker* tracker_;
};

namespace {

class Factory : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit Factory(CallTracker* tracker) : tracker_(tracker) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(grpc::experimental::ServerRpcInfo*) override {
    return new CallCountingInterceptor(tracker_);
  }

 private:
  CallTracker* tracker_;
};

}  // namespace

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> CallTracker::interceptor_factory() {
  return std::make_unique<Factory>(this);
}

}  // namespace gdvr::server
