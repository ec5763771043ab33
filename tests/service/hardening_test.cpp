// Service hardening (issue 38): limits on what is actually rendered, bounded
// error text, prompt shutdown with health Watch streams open, the health
// service name and reflection v1, upload folder and quotas, client-facing
// paths, CANCELLING, and the two progress stages in the events.
#include <gtest/gtest.h>
#include <signal.h>

#include <google/protobuf/descriptor.pb.h>
#include <grpcpp/generic/generic_stub.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "client/progress_view.h"
#include "core/io/image_io.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "grpc/reflection/v1/reflection.grpc.pb.h"
#include "tests/service/rpc_helpers.h"
#include "tests/service/server_process.h"

namespace gdvr::testing {
namespace {
namespace fs = std::filesystem;
using grpc::StatusCode;

std::string slurp_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

void expect_contains(const std::string& text, const std::string& needle, const std::string& what) {
  EXPECT_NE(text.find(needle), std::string::npos) << what << ": '" << text << "' does not mention '" << needle << "'";
}

// A Cornell box whose sampler and film are literal values, not $params.
const char* kLiteralScene = R"(<scene version="3.0.0">
  <include filename="fragments/bsdfs-rgb.xml"/>
  <include filename="fragments/shapes.xml"/>
  <emitter type="area" id="area-emitter"><rgb name="radiance" value="18.387, 10.9873, 2.75357"/></emitter>
  <sensor type="perspective">
    <transform name="to_world"><lookat origin="278, 273, -800" target="278, 273, -799" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="256"/></sampler>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/></film>
  </sensor>
</scene>
)";

// Self-contained (no other file): what an upload bundle holds.
std::string sphere_scene(int spp, const std::string& extra = "") {
  return R"(<scene version="3.0.0">
  <sensor type="perspective">
    <transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value=")" +
         std::to_string(spp) + R"("/></sampler>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>
  <shape type="sphere"/>
)" + extra + "</scene>\n";
}

// ---- 1. Limits apply to what will be rendered ----

TEST(ServiceLimits, ResolvedSceneValuesAreLimited) {
  TestDir dir;
  { std::ofstream(dir.assets() + "/cbox/literal.xml") << kLiteralScene; }
  ServerProcess server(dir, {"--max-width=128", "--max-height=128", "--max-spp=64", "--max-time-budget=60",
                             "--max-work=2000000"});
  ASSERT_TRUE(server.start());
  auto stub = server.stub();
  struct Case {
    const char* name;
    std::string json;
    std::vector<std::string> mentions;
  };
  // cbox-rgb.xml: <default name="res" value="256"/>, <default name="spp" value="256"/>.
  const std::vector<Case> refused = {
      {"params.res with width unset",
       R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "spp": 2, "params": {"res": "512"}})",
       {"width: 512", "params.res", "--max-width"}},
      {"params.spp with spp unset",
       R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 32, "height": 32, "params": {"spp": "1000"}})",
       {"spp: 1000", "params.spp", "--max-spp"}},
      {"the scene's <default> spp",
       R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 32, "height": 32})",
       {"spp: 256", "<default name=\"spp\">", "cbox/fragments/base.xml:", "--max-spp"}},
      {"the scene's literal sample_count", R"({"scene": "cbox/literal.xml", "frames": "1"})",
       {"spp: 256", "the scene (cbox/literal.xml:", "--max-spp"}},
      {"the scene's width with height set",
       R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "height": 32, "spp": 2})",
       {"width: 256", "<default name=\"res\">", "--max-width"}},
      {"time budget", R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 32, "height": 32, "spp": 2, "time_budget_s": 1e9})",
       {"time_budget_s", "--max-time-budget"}},
      {"total work",
       R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-100", "width": 128, "height": 128, "spp": 2})",
       {"100 frames x 128x128 x 2 spp", "--max-work"}},
  };
  for (const auto& c : refused) {
    v1::SubmitJobResponse resp;
    grpc::Status st = submit_json(stub.get(), std::string("lim-") + c.name, c.json, &resp);
    EXPECT_EQ(st.error_code(), StatusCode::RESOURCE_EXHAUSTED) << c.name << ": " << st.error_message();
    for (const auto& m : c.mentions) expect_contains(st.error_message(), m, c.name);
    EXPECT_EQ(st.error_message().find(dir.path()), std::string::npos) << st.error_message();
  }
  // direct_light strata below 0 are refused, through job_json and the proto alike.
  for (const char* dl : {R"({"strata": -1})", R"({"strata": -7})", R"({"edge_strata": -1})"}) {
    v1::SubmitJobResponse resp;
    grpc::Status st = submit_json(
        stub.get(), std::string("dl-") + dl,
        std::string(R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 16, "height": 16, "spp": 1, "direct_light": )") +
            dl + "}",
        &resp);
    EXPECT_EQ(st.error_code(), StatusCode::INVALID_ARGUMENT) << dl << ": " << st.error_message();
    expect_contains(st.error_message(), "direct_light", dl);
  }
  v1::JobSpec spec;
  spec.set_scene("cbox/cbox-rgb.xml");
  spec.set_frames("1");
  spec.set_width(16);
  spec.set_height(16);
  spec.set_spp(1);
  spec.mutable_direct_light()->set_strata(-3);
  v1::SubmitJobResponse resp;
  grpc::Status st = submit_spec(stub.get(), "dl-proto", spec, &resp);
  EXPECT_EQ(st.error_code(), StatusCode::INVALID_ARGUMENT) << st.error_message();
  expect_contains(st.error_message(), "direct_light.strata", "proto strata -3");

  // Within the limits a params override is taken, and renders at its size.
  st = submit_json(stub.get(), "lim-ok",
                   R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "spp": 1, "params": {"res": "48"}})", &resp);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_EQ(wait_terminal(stub.get(), resp.job_id()), "completed");
  auto img = read_exr(dir.out() + "/" + resp.job_id() + "/frame_0001.exr");
  ASSERT_TRUE(img.ok()) << img.status().to_string();
  ASSERT_NE(img->find(""), nullptr);
  EXPECT_EQ(img->find("")->image.width(), 48);
  EXPECT_EQ(health_status(server.channel()), "SERVING");
}

// ---- 2. Echoed input is bounded and escaped, in statuses and the log ----

TEST(ServiceInput, LongAndControlInputIsBoundedInStatusAndLog) {
  TestDir dir;
  ServerProcess server(dir);
  ASSERT_TRUE(server.start());
  // A client with gRPC's default metadata limits (the test helper's channel
  // only raises the message size).
  auto stub = v1::RenderService::NewStub(grpc::CreateChannel(server.address(), grpc::InsecureChannelCredentials()));
  const std::string long_text(20000, 'x');
  struct Case {
    const char* name;
    std::string json;
    StatusCode code;
    std::string mentions;
  };
  const std::vector<Case> cases = {
      {"20,000-character scene", R"({"scene": ")" + long_text + R"(.xml"})", StatusCode::INVALID_ARGUMENT,
       "(20004 characters)"},
      {"20,000-character unknown field", R"({"scene": "cbox/cbox-rgb.xml", ")" + long_text + R"(": 1})",
       StatusCode::INVALID_ARGUMENT, "(20000 characters)"},
      {"20,000-character frames", R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-)" + long_text + R"("})",
       StatusCode::INVALID_ARGUMENT, "(20002 characters)"},
      {"20,000-character integrator", R"({"scene": "cbox/cbox-rgb.xml", "integrator": ")" + long_text + R"("})",
       StatusCode::INVALID_ARGUMENT, "(20000 characters)"},
      {"NUL and newline in the scene", R"({"scene": "cbox/a\u0000b\nc.xml"})", StatusCode::INVALID_ARGUMENT,
       "cbox/a\\x00b\\nc.xml"},
  };
  for (const auto& c : cases) {
    v1::SubmitJobResponse resp;
    grpc::Status st = submit_json(stub.get(), "", c.json, &resp);
    EXPECT_EQ(st.error_code(), c.code) << c.name << ": " << st.error_message().substr(0, 300);
    EXPECT_LT(st.error_message().size(), 1000u) << c.name;
    expect_contains(st.error_message(), c.mentions, c.name);
    EXPECT_EQ(st.error_message().find('\0'), std::string::npos) << c.name;
  }
  {
    auto ctx = rpc_context();
    v1::GetJobRequest req;
    req.set_job_id(long_text);
    v1::Job job;
    grpc::Status st = stub->GetJob(ctx.get(), req, &job);
    EXPECT_EQ(st.error_code(), StatusCode::NOT_FOUND) << st.error_message().substr(0, 300);
    EXPECT_LT(st.error_message().size(), 1000u);
  }
  // The log: one line per event, bounded, no raw NUL; the NUL shows escaped.
  std::string log = slurp_file(server.log_path());
  EXPECT_EQ(log.find('\0'), std::string::npos);
  expect_contains(log, "\\\\x00", "server log");  // logfmt quoting doubles the escape's backslash
  std::istringstream lines(log);
  std::string line;
  size_t longest = 0;
  while (std::getline(lines, line)) longest = std::max(longest, line.size());
  EXPECT_LT(longest, 12000u) << "a log line of " << longest << " bytes";
}

// ---- 3. Health: Watch streams end on SIGTERM; the service name; reflection v1 ----

TEST(ServiceShutdown, OpenHealthWatchDoesNotHoldShutdown) {
  TestDir dir;
  const double grace_s = 6;
  ServerProcess server(dir, {"--shutdown-grace-s=6"});
  ASSERT_TRUE(server.start());
  auto channel = server.channel();
  auto health = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext ctx_all, ctx_named;
  grpc::health::v1::HealthCheckRequest all, named;
  named.set_service("gdvr.v1.RenderService");
  auto watch_all = health->Watch(&ctx_all, all);
  auto watch_named = health->Watch(&ctx_named, named);
  grpc::health::v1::HealthCheckResponse r;
  ASSERT_TRUE(watch_all->Read(&r));
  EXPECT_EQ(r.status(), grpc::health::v1::HealthCheckResponse::SERVING);
  ASSERT_TRUE(watch_named->Read(&r));
  EXPECT_EQ(r.status(), grpc::health::v1::HealthCheckResponse::SERVING);

  auto t0 = std::chrono::steady_clock::now();
  int exit_status = -2;
  std::thread stop([&] { exit_status = server.terminate(); });
  // Each watcher learns NOT_SERVING, then its stream ends.
  for (auto* w : {watch_all.get(), watch_named.get()}) {
    std::vector<int> seen;
    while (w->Read(&r)) seen.push_back(int(r.status()));
    EXPECT_EQ(seen, (std::vector<int>{grpc::health::v1::HealthCheckResponse::NOT_SERVING}));
    EXPECT_EQ(w->Finish().error_code(), StatusCode::UNAVAILABLE);
  }
  stop.join();
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(exit_status, 0);
  // Before: the whole grace period (3.0/5.1/10.1 s for 3/5/10). The client's
  // channel stays open and idle throughout, as a prober's would.
  EXPECT_LT(seconds, 1.5) << "shutdown with two health Watch streams open took " << seconds << " s (grace "
                          << grace_s << " s)";
  std::printf("[ measured ] shutdown with 2 health Watch streams open: %.3f s (grace %.0f s)\n", seconds, grace_s);
}

// v1 reflection requests have the v1alpha wire format: a bidi call on the
// v1alpha method with v1 message types.
std::vector<grpc::reflection::v1::ServerReflectionResponse> reflect(
    const std::shared_ptr<grpc::Channel>& channel, const std::string& method,
    const std::vector<grpc::reflection::v1::ServerReflectionRequest>& requests) {
  using Req = grpc::reflection::v1::ServerReflectionRequest;
  using Resp = grpc::reflection::v1::ServerReflectionResponse;
  grpc::TemplatedGenericStub<Req, Resp> stub(channel);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  grpc::CompletionQueue cq;
  void* tag;
  bool ok;
  auto call = stub.PrepareCall(&ctx, method, &cq);
  call->StartCall(reinterpret_cast<void*>(1));
  cq.Next(&tag, &ok);
  std::vector<Resp> out;
  for (const auto& req : requests) {
    call->Write(req, reinterpret_cast<void*>(2));
    cq.Next(&tag, &ok);
    Resp resp;
    call->Read(&resp, reinterpret_cast<void*>(3));
    cq.Next(&tag, &ok);
    if (ok) out.push_back(resp);
  }
  call->WritesDone(reinterpret_cast<void*>(4));
  cq.Next(&tag, &ok);
  grpc::Status st;
  call->Finish(&st, reinterpret_cast<void*>(5));
  cq.Next(&tag, &ok);
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {}
  return out;
}

TEST(ServiceHealth, ServiceNameAndReflectionV1) {
  TestDir dir;
  ServerProcess server(dir);
  ASSERT_TRUE(server.start());
  auto health = grpc::health::v1::Health::NewStub(server.channel());
  {
    grpc::ClientContext ctx;
    grpc::health::v1::HealthCheckRequest req;
    req.set_service("gdvr.v1.RenderService");
    grpc::health::v1::HealthCheckResponse resp;
    grpc::Status st = health->Check(&ctx, req, &resp);
    ASSERT_TRUE(st.ok()) << st.error_message();  // NOT_FOUND before
    EXPECT_EQ(resp.status(), grpc::health::v1::HealthCheckResponse::SERVING);
  }
  {
    grpc::ClientContext ctx;
    grpc::health::v1::HealthCheckRequest req;
    req.set_service("no.such.Service");
    grpc::health::v1::HealthCheckResponse resp;
    EXPECT_EQ(health->Check(&ctx, req, &resp).error_code(), StatusCode::NOT_FOUND);
  }
  grpc::reflection::v1::ServerReflectionRequest list, symbol, v1alpha_file;
  list.set_list_services("");
  symbol.set_file_containing_symbol("gdvr.v1.RenderService");
  v1alpha_file.set_file_containing_symbol("grpc.reflection.v1alpha.ServerReflectionRequest");
  // v1 (UNIMPLEMENTED before) and v1alpha both list the services and describe them.
  for (const std::string service : {"grpc.reflection.v1.ServerReflection", "grpc.reflection.v1alpha.ServerReflection"}) {
    auto resps = reflect(server.channel(), "/" + service + "/ServerReflectionInfo", {list, symbol});
    ASSERT_EQ(resps.size(), 2u) << service;
    std::set<std::string> names;
    for (const auto& s : resps[0].list_services_response().service()) names.insert(s.name());
    EXPECT_TRUE(names.count("gdvr.v1.RenderService")) << service;
    EXPECT_TRUE(names.count("grpc.health.v1.Health")) << service;
    std::set<std::string> files;
    for (const auto& bytes : resps[1].file_descriptor_response().file_descriptor_proto()) {
      google::protobuf::FileDescriptorProto f;
      ASSERT_TRUE(f.ParseFromString(bytes));
      files.insert(f.name());
    }
    EXPECT_TRUE(files.count("gdvr/v1/render_service.proto")) << service;
    EXPECT_TRUE(files.count("gdvr/v1/job.proto")) << service;  // and what it imports
  }
  // Our v1 messages are v1alpha's, field for field (what makes them
  // interchangeable on the wire): compared with the server's own v1alpha file.
  auto resps = reflect(server.channel(), "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
                       {v1alpha_file});
  ASSERT_EQ(resps.size(), 1u);
  ASSERT_GE(resps[0].file_descriptor_response().file_descriptor_proto_size(), 1);
  google::protobuf::FileDescriptorProto alpha, ours;
  ASSERT_TRUE(alpha.ParseFromString(resps[0].file_descriptor_response().file_descriptor_proto(0)));
  grpc::reflection::v1::ServerReflectionRequest::descriptor()->file()->CopyTo(&ours);
  std::map<std::string, const google::protobuf::DescriptorProto*> ours_by_name;
  for (const auto& m : ours.message_type()) ours_by_name[m.name()] = &m;
  ASSERT_EQ(alpha.message_type_size(), ours.message_type_size());
  for (const auto& m : alpha.message_type()) {
    ASSERT_TRUE(ours_by_name.count(m.name())) << m.name();
    const auto& o = *ours_by_name[m.name()];
    ASSERT_EQ(m.field_size(), o.field_size()) << m.name();
    for (int i = 0; i < m.field_size(); ++i) {
      EXPECT_EQ(m.field(i).name(), o.field(i).name()) << m.name();
      EXPECT_EQ(m.field(i).number(), o.field(i).number()) << m.name() << "." << m.field(i).name();
      EXPECT_EQ(m.field(i).type(), o.field(i).type()) << m.name() << "." << m.field(i).name();
      EXPECT_EQ(m.field(i).label(), o.field(i).label()) << m.name() << "." << m.field(i).name();
    }
  }
}

// ---- 5. Uploads: own folder, quotas, retention ----

TEST(ServiceUploads, OwnFolderQuotasAndRetention) {
  TestDir dir;
  ServerProcess server(dir, {"--upload-quota-files=5", "--upload-retention-s=2"});
  ASSERT_TRUE(server.start());
  auto stub = server.stub();
  v1::UploadSceneResponse a, b, c, d;
  ASSERT_TRUE(upload(stub.get(), "a.xml", {{"a.xml", sphere_scene(1)}}, &a).ok());
  // In the upload folder (<output-root>/uploads), not in the asset root.
  const std::string uploads = dir.out() + "/uploads/";
  EXPECT_EQ(a.scene(), "uploads/" + a.bundle_hash() + "/a.xml");
  EXPECT_TRUE(fs::exists(uploads + a.bundle_hash() + "/a.xml"));
  EXPECT_FALSE(fs::exists(dir.assets() + "/uploads"));
  v1::SubmitJobResponse job;
  ASSERT_TRUE(submit_json(stub.get(), "up-a", R"({"scene": ")" + a.scene() + R"(", "frames": "1"})", &job).ok());
  EXPECT_EQ(wait_terminal(stub.get(), job.job_id()), "completed");
  // A bundle's scene may not reach outside its bundle (here: into the asset root).
  ASSERT_TRUE(upload(stub.get(), "b.xml",
                     {{"b.xml", sphere_scene(1, R"(<shape type="obj"><string name="filename" )"
                                                R"(value="../../../assets/cbox/meshes/cbox_floor.obj"/></shape>)")}},
                     &b)
                  .ok());
  grpc::Status st = submit_json(stub.get(), "up-b", R"({"scene": ")" + b.scene() + R"(", "frames": "1"})", &job);
  EXPECT_EQ(st.error_code(), StatusCode::INVALID_ARGUMENT) << st.error_message();
  // 2 files held; 4 more would pass the quota of 5.
  std::vector<UploadFile> four = {{"c.xml", sphere_scene(1)}, {"x/1.txt", "1"}, {"x/2.txt", "2"}, {"x/3.txt", "3"}};
  st = upload(stub.get(), "c.xml", four, &c);
  EXPECT_EQ(st.error_code(), StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  expect_contains(st.error_message(), "--upload-quota-files", "quota");
  // A bundle a running job names is kept past the retention.
  ASSERT_TRUE(upload(stub.get(), "d.xml", {{"d.xml", sphere_scene(4000)}}, &d).ok());
  ASSERT_TRUE(
      submit_json(stub.get(), "up-d", R"({"scene": ")" + d.scene() + R"(", "frames": "1-50", "width": 64, "height": 64})",
                  &job)
          .ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  // Now a and b (no unfinished job names them) have expired, and their room is free.
  st = upload(stub.get(), "c.xml", four, &c);
  EXPECT_TRUE(st.ok()) << st.error_message();
  EXPECT_FALSE(fs::exists(uploads + a.bundle_hash()));
  EXPECT_FALSE(fs::exists(uploads + b.bundle_hash()));
  EXPECT_TRUE(fs::exists(uploads + d.bundle_hash())) << "a bundle in use was deleted";
  EXPECT_TRUE(fs::exists(uploads + c.bundle_hash() + "/x/3.txt"));
  auto ctx = rpc_context();
  v1::CancelJobRequest creq;
  creq.set_job_id(job.job_id());
  v1::Job cancelled;
  EXPECT_TRUE(stub->CancelJob(ctx.get(), creq, &cancelled).ok());
  // A path component no file system takes is the request's fault.
  st = upload(stub.get(), "s.xml", {{std::string(300, 'p') + "/s.xml", "<scene/>"}}, &c);
  EXPECT_EQ(st.error_code(), StatusCode::INVALID_ARGUMENT) << st.error_message();  // INTERNAL before
}

// ---- 6. Client messages show server files by relative names ----

TEST(ServiceErrors, ShowPathsRelativeToTheAssetRoot) {
  TestDir dir;
  { std::ofstream(dir.assets() + "/broken.xml") << "<scene version=\"3.0.0\"><shape type="; }
  {
    std::ofstream(dir.assets() + "/cbox/missing-mesh.xml")
        << R"(<scene version="3.0.0"><shape type="obj"><string name="filename" value="meshes/nope.obj"/></shape></scene>)";
  }
  ServerProcess server(dir);
  ASSERT_TRUE(server.start());
  auto stub = server.stub();
  struct Case {
    const char* name;
    std::string json, mentions;
  };
  const std::vector<Case> cases = {
      {"malformed XML", R"({"scene": "broken.xml"})", "broken.xml:1"},
      {"missing mesh", R"({"scene": "cbox/missing-mesh.xml"})", "nope.obj"},
      {"unknown OCIO view", R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 16, "height": 16, "spp": 1, "outputs": {"ocio_view": "No Such View"}})",
       "<ocio-config>"},
      {"over the size limit", R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "spp": 1, "width": 100000})", "width"},
  };
  for (const auto& c : cases) {
    v1::SubmitJobResponse resp;
    grpc::Status st = submit_json(stub.get(), std::string("paths-") + c.name, c.json, &resp);
    EXPECT_FALSE(st.ok()) << c.name;
    expect_contains(st.error_message(), c.mentions, c.name);
    EXPECT_EQ(st.error_message().find(dir.path()), std::string::npos) << c.name << ": " << st.error_message();
    EXPECT_EQ(st.error_message().find(GDVR_SOURCE_DIR), std::string::npos) << c.name << ": " << st.error_message();
  }
  // The server log keeps the absolute path, for the operator.
  expect_contains(slurp_file(server.log_path()), dir.assets() + "/broken.xml:1", "server log");
}

// ---- 7. CancelJob answers with the state the job is moving to ----

TEST(ServiceCancel, RunningBecomesCancellingQueuedBecomesCancelled) {
  TestDir dir;
  ServerProcess server(dir, {"--concurrency=1"});
  ASSERT_TRUE(server.start());
  auto stub = server.stub();
  const char* slow = R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-20", "width": 96, "height": 96, "spp": 64})";
  v1::SubmitJobResponse running, queued;
  ASSERT_TRUE(submit_json(stub.get(), "run", slow, &running).ok());
  ASSERT_TRUE(submit_json(stub.get(), "wait", slow, &queued).ok());
  for (int i = 0; i < 100; ++i) {  // until the first job runs
    auto ctx = rpc_context();
    v1::GetJobRequest req;
    req.set_job_id(running.job_id());
    v1::Job j;
    ASSERT_TRUE(stub->GetJob(ctx.get(), req, &j).ok());
    if (j.state() == v1::JOB_STATE_RUNNING) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  auto cancel = [&](const std::string& id) {
    auto ctx = rpc_context();
    v1::CancelJobRequest req;
    req.set_job_id(id);
    v1::Job j;
    grpc::Status st = stub->CancelJob(ctx.get(), req, &j);
    EXPECT_TRUE(st.ok()) << st.error_message();
    return j.state();
  };
  EXPECT_EQ(cancel(queued.job_id()), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(cancel(running.job_id()), v1::JOB_STATE_CANCELLING);  // RUNNING before
  {
    // GetJob agrees until the render stops; ListJobs can select it.
    auto ctx = rpc_context();
    v1::GetJobRequest req;
    req.set_job_id(running.job_id());
    v1::Job j;
    ASSERT_TRUE(stub->GetJob(ctx.get(), req, &j).ok());
    EXPECT_TRUE(j.state() == v1::JOB_STATE_CANCELLING || j.state() == v1::JOB_STATE_CANCELLED) << j.state();
  }
  EXPECT_EQ(wait_terminal(stub.get(), running.job_id()), "cancelled");
  EXPECT_EQ(wait_terminal(stub.get(), queued.job_id()), "cancelled");
}

// ---- 8. Progress events count both stages ----

TEST(ServiceProgress, EventsCountRenderedAndFinalFrames) {
  TestDir dir;
  fs::copy(std::string(GDVR_SOURCE_DIR) + "/scenes/demo", dir.assets() + "/demo", fs::copy_options::recursive);
  ServerProcess server(dir);
  ASSERT_TRUE(server.start());
  auto stub = server.stub();
  const char* job = R"({"scene": "demo/cbox_demo.xml", "frames": "0-11", "spp": 2, "seed": 1, "integrator": "tgpt",
    "params": {"res": "32"}, "reconstruction": {"method": "l2", "window": 6},
    "tracks": [{"target": "smallbox", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 11, "translate": [-70, 0, -60]}]}]})";
  v1::SubmitJobResponse resp;
  grpc::Status st = submit_json(stub.get(), "tgpt", job, &resp);
  ASSERT_TRUE(st.ok()) << st.error_message();
  auto ctx = rpc_context("", 240);
  v1::WatchJobRequest req;
  req.set_job_id(resp.job_id());
  auto reader = stub->WatchJob(ctx.get(), req);
  v1::JobEvent ev;
  client::ProgressView view;
  auto t0 = std::chrono::steady_clock::now();
  int finals = 0;
  bool lag_seen = false;
  while (reader->Read(&ev)) {
    double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    view.on_event(ev, t);
    const v1::Progress* p = nullptr;
    if (ev.has_frame_rendered()) p = &ev.frame_rendered().progress();
    if (ev.has_frame_final() && ev.frame_final().last()) {
      p = &ev.frame_final().progress();
      ++finals;
      // Each frame says the final count as of itself.
      EXPECT_EQ(p->frames_done(), finals) << "frame " << ev.frame_final().frame();
      EXPECT_EQ(view.frames_final(), finals);
      if (finals < 12) EXPECT_NE(view.eta_seconds(t), 0.0) << "ETA 0 with frames still to come";
      else EXPECT_EQ(view.eta_seconds(t), 0.0);
    }
    if (p) {
      EXPECT_GE(p->frames_rendered(), p->frames_done());
      EXPECT_LE(p->frames_rendered(), 12);
      lag_seen |= p->frames_rendered() > p->frames_done();
    }
  }
  EXPECT_TRUE(reader->Finish().ok());
  EXPECT_EQ(finals, 12);
  EXPECT_TRUE(lag_seen) << "a tgpt job's final frames never trailed its rendered ones";
}

}  // namespace
}  // namespace gdvr::testing
