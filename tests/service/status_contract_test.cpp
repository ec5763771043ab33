// docs/service.md's status-code table is the contract: this test reads the
// table and makes, for every row, the request that row describes, expecting
// the row's code. A row without a request here, or a request without a row
// there, fails the test, so the two cannot drift apart.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "tests/service/rpc_helpers.h"
#include "tests/service/server_process.h"

namespace gdvr::testing {
namespace {
namespace fs = std::filesystem;
using grpc::StatusCode;

const char* kToken = "contract-token";
const char* kTiny = R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 16, "height": 16, "spp": 1})";
const char* kSlow = R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-8", "width": 96, "height": 96, "spp": 48})";

struct Row {
  std::string code, when;
};

// The rows of the table under "### Status codes": case id -> code.
std::map<std::string, Row> documented_rows() {
  std::ifstream in(std::string(GDVR_SOURCE_DIR) + "/docs/service.md");
  std::string line;
  bool in_section = false;
  std::map<std::string, Row> rows;
  const std::regex row(R"(^\| `([a-z0-9-]+)` \| `([A-Z_]+)` \| (.*) \|$)");
  while (std::getline(in, line)) {
    if (line.rfind("### Status codes", 0) == 0) in_section = true;
    else if (in_section && line.rfind("#", 0) == 0) break;
    std::smatch m;
    if (in_section && std::regex_match(line, m, row)) rows[m[1]] = {m[2], m[3]};
  }
  return rows;
}

StatusCode code_from_name(const std::string& name) {
  static const std::map<std::string, StatusCode> codes = {
      {"INVALID_ARGUMENT", StatusCode::INVALID_ARGUMENT}, {"NOT_FOUND", StatusCode::NOT_FOUND},
      {"FAILED_PRECONDITION", StatusCode::FAILED_PRECONDITION}, {"RESOURCE_EXHAUSTED", StatusCode::RESOURCE_EXHAUSTED},
      {"UNIMPLEMENTED", StatusCode::UNIMPLEMENTED}, {"UNAUTHENTICATED", StatusCode::UNAUTHENTICATED},
      {"UNAVAILABLE", StatusCode::UNAVAILABLE}, {"INTERNAL", StatusCode::INTERNAL}};
  auto it = codes.find(name);
  return it == codes.end() ? StatusCode::UNKNOWN : it->second;
}

class Contract {
 public:
  Contract()
      : server_(dir_,
                {"--max-width=128", "--max-height=128", "--max-spp=64", "--max-frames=1000", "--max-time-budget=60",
                 "--max-work=5000000", "--max-upload-bytes=20000", "--upload-quota-bytes=30000", "--max-queue=1",
                 "--concurrency=1"},
                {{"GDVR_TOKENS", kToken}}) {
    { std::ofstream(dir_.assets() + "/broken.xml") << "<scene version=\"3.0.0\"><shape type="; }
    { std::ofstream(dir_.assets() + "/principled.xml") << "<scene version=\"3.0.0\"><bsdf type=\"principled\"/></scene>"; }
    { std::ofstream(dir_.assets() + "/cbox/notes.txt") << "not a scene"; }
    { std::ofstream(dir_.assets() + "/garbage.exr", std::ios::binary) << "not an OpenEXR file"; }
    { std::ofstream(dir_.path() + "/outside.xml") << "<scene version=\"3.0.0\"/>"; }
  }
  bool start() { return server_.start(); }
  v1::RenderService::Stub* stub() {
    if (!stub_) stub_ = server_.stub();
    return stub_.get();
  }
  grpc::Status submit(const std::string& json, std::string* id = nullptr) {
    v1::SubmitJobResponse resp;
    grpc::Status st = submit_json(stub(), "contract-" + std::to_string(++keys_), json, &resp, kToken);
    if (id) *id = resp.job_id();
    return st;
  }
  grpc::Status submit_keyed(const std::string& key, const std::string& json) {
    v1::SubmitJobResponse resp;
    return submit_json(stub(), key, json, &resp, kToken);
  }
  grpc::Status job_with(const std::string& fields) {
    return submit(R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 16, "height": 16, "spp": 1, )" + fields +
                  "}");
  }
  grpc::Status upload_files(const std::vector<UploadFile>& files) {
    v1::UploadSceneResponse resp;
    return upload(stub(), "s.xml", files, &resp, kToken);
  }
  TestDir& dir() { return dir_; }

 private:
  TestDir dir_;
  ServerProcess server_;
  std::unique_ptr<v1::RenderService::Stub> stub_;
  int keys_ = 0;
};

// One request per documented row. Run in this order: the stateful cases
// (uploads filling the quota, the queue) come last.
std::vector<std::pair<std::string, std::function<grpc::Status(Contract&)>>> cases() {
  using C = Contract;
  return {
      {"not-json", [](C& c) { return c.submit("{scene:"); }},
      {"unknown-field", [](C& c) { return c.job_with(R"("outputs": {"codec": "h264"})"); }},
      {"bad-frames", [](C& c) { return c.submit(R"({"scene": "cbox/cbox-rgb.xml", "frames": "5-1"})"); }},
      {"no-scene", [](C& c) { return c.submit(R"({"frames": "1"})"); }},
      {"scene-extension", [](C& c) { return c.submit(R"({"scene": "cbox/notes.txt"})"); }},
      {"scene-nul", [](C& c) { return c.submit(R"({"scene": "cbox/cbox\u0000rgb.xml"})"); }},
      {"scene-long-component",
       [](C& c) { return c.submit(R"({"scene": "cbox/)" + std::string(300, 'a') + R"(.xml"})"); }},
      {"scene-outside", [](C& c) { return c.submit(R"({"scene": "../outside.xml"})"); }},
      {"bad-upload-scene", [](C& c) { return c.submit(R"({"scene": "uploads/not-a-hash/s.xml"})"); }},
      {"malformed-xml", [](C& c) { return c.submit(R"({"scene": "broken.xml"})"); }},
      {"unknown-name", [](C& c) { return c.job_with(R"("integrator": "magic")"); }},
      {"bad-reference", [](C& c) { return c.job_with(R"("reference": "garbage.exr")"); }},
      {"unknown-track-target",
       [](C& c) {
         return c.job_with(R"("tracks": [{"target": "no-such-id", "keys": [{"time": 0, "translate": [0, 0, 0]}]}])");
       }},
      {"negative-value", [](C& c) { return c.submit(R"({"scene": "cbox/cbox-rgb.xml", "spp": -4})"); }},
      {"bad-direct-light", [](C& c) { return c.job_with(R"("direct_light": {"strata": -1})"); }},
      {"long-key", [](C& c) { return c.submit_keyed(std::string(300, 'k'), kTiny); }},
      {"bad-page-token",
       [](C& c) {
         auto ctx = rpc_context(kToken);
         v1::ListJobsRequest req;
         req.set_page_token("garbage");
         v1::ListJobsResponse resp;
         return c.stub()->ListJobs(ctx.get(), req, &resp);
       }},
      {"bad-artifact-kind",
       [](C& c) {
         auto ctx = rpc_context(kToken);
         v1::FetchArtifactsRequest req;
         req.set_job_id("job-unknown");
         req.add_kinds(v1::ArtifactKind(99));
         auto reader = c.stub()->FetchArtifacts(ctx.get(), req);
         v1::ArtifactChunk chunk;
         while (reader->Read(&chunk)) {}
         return reader->Finish();
       }},
      {"bad-upload-path", [](C& c) { return c.upload_files({{std::string(300, 'p') + ".xml", "<scene/>"}}); }},
      {"scene-not-found", [](C& c) { return c.submit(R"({"scene": "cbox/nope.xml"})"); }},
      {"reference-not-found", [](C& c) { return c.job_with(R"("reference": "cbox/nope.exr")"); }},
      {"job-not-found",
       [](C& c) {
         auto ctx = rpc_context(kToken);
         v1::GetJobRequest req;
         req.set_job_id("job-unknown");
         v1::Job job;
         return c.stub()->GetJob(ctx.get(), req, &job);
       }},
      {"key-reused",
       [](C& c) {
         grpc::Status first = c.submit_keyed("reused", kTiny);
         if (!first.ok()) return first;
         return c.submit_keyed("reused", R"({"scene": "cbox/cbox-rgb.xml", "frames": "2", "width": 16, "height": 16, "spp": 1})");
       }},
      {"cancel-finished",
       [](C& c) {
         std::string id;
         grpc::Status st = c.submit(kTiny, &id);
         if (!st.ok()) return st;
         if (wait_terminal(c.stub(), id, kToken) != "completed") return grpc::Status(StatusCode::UNKNOWN, "not completed");
         auto ctx = rpc_context(kToken);
         v1::CancelJobRequest req;
         req.set_job_id(id);
         v1::Job job;
         return c.stub()->CancelJob(ctx.get(), req, &job);
       }},
      {"over-size-limit",
       [](C& c) {
         return c.submit(R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "spp": 1, "params": {"res": "512"}})");
       }},
      {"over-frame-limit", [](C& c) { return c.submit(R"({"scene": "cbox/cbox-rgb.xml", "frames": "0-2147483647"})"); }},
      {"over-time-budget", [](C& c) { return c.job_with(R"("time_budget_s": 1e9)"); }},
      {"over-work-limit",
       [](C& c) {
         return c.submit(R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-100", "width": 128, "height": 128, "spp": 64})");
       }},
      {"unsupported-feature", [](C& c) { return c.submit(R"({"scene": "principled.xml"})"); }},
      {"bad-token",
       [](C& c) {
         v1::SubmitJobResponse resp;
         return submit_json(c.stub(), "no-token", kTiny, &resp, "wrong-token");
       }},
      {"upload-too-big", [](C& c) { return c.upload_files({{"s.xml", std::string(25000, 'x')}}); }},
      {"upload-quota",
       [](C& c) {
         grpc::Status first = c.upload_files({{"s.xml", std::string(15000, 'a')}});
         if (!first.ok()) return first;
         return c.upload_files({{"s.xml", std::string(16000, 'b')}});
       }},
      {"queue-full",
       [](C& c) {
         // One running, one waiting (--max-queue=1): the next is refused.
         std::string running, waiting;
         grpc::Status st = c.submit(kSlow, &running);
         if (!st.ok()) return st;
         std::this_thread::sleep_for(std::chrono::milliseconds(500));
         st = c.submit(kSlow, &waiting);
         if (!st.ok()) return st;
         grpc::Status full = c.submit(kSlow);
         for (const std::string& id : {running, waiting}) {
           auto ctx = rpc_context(kToken);
           v1::CancelJobRequest req;
           req.set_job_id(id);
           v1::Job job;
           (void)c.stub()->CancelJob(ctx.get(), req, &job);
         }
         return full;
       }},
  };
}

// Its own server: it is stopped while a client watches.
grpc::Status shutting_down() {
  TestDir dir;
  ServerProcess server(dir);
  if (!server.start()) return grpc::Status(StatusCode::UNKNOWN, "server did not start");
  auto stub = server.stub();
  v1::SubmitJobResponse resp;
  grpc::Status st = submit_json(stub.get(), "stop", kSlow, &resp);
  if (!st.ok()) return st;
  auto ctx = rpc_context("", 60);
  v1::WatchJobRequest req;
  req.set_job_id(resp.job_id());
  auto reader = stub->WatchJob(ctx.get(), req);
  v1::JobEvent ev;
  if (!reader->Read(&ev)) return reader->Finish();
  std::thread stop([&] { server.terminate(); });
  while (reader->Read(&ev)) {}
  grpc::Status end = reader->Finish();
  stop.join();
  return end;
}

TEST(ServiceStatusContract, EveryDocumentedRowHolds) {
  const auto rows = documented_rows();
  ASSERT_GE(rows.size(), 30u) << "the status table in docs/service.md was not found or lost rows";
  Contract c;
  ASSERT_TRUE(c.start());
  std::set<std::string> tested;
  auto check = [&](const std::string& id, const grpc::Status& st) {
    tested.insert(id);
    auto row = rows.find(id);
    if (row == rows.end()) {
      ADD_FAILURE() << "case '" << id << "' is tested but has no row in docs/service.md";
      return;
    }
    EXPECT_EQ(st.error_code(), code_from_name(row->second.code))
        << "row '" << id << "' (" << row->second.when << "): got code " << int(st.error_code()) << " '"
        << st.error_message() << "'";
    EXPECT_FALSE(st.error_message().empty()) << id;
    EXPECT_LT(st.error_message().size(), 2048u) << id;
  };
  for (auto& [id, run] : cases()) check(id, run(c));
  check("shutting-down", shutting_down());
  for (const auto& [id, row] : rows)
    EXPECT_TRUE(tested.count(id)) << "docs/service.md row '" << id << "' (" << row.code << ") has no request here";
}

}  // namespace
}  // namespace gdvr::testing
