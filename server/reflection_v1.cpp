#include "server/reflection_v1.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>

#include <set>

namespace gdvr::server {
namespace {

namespace pb = google::protobuf;
using grpc::reflection::v1::ServerReflectionRequest;
using grpc::reflection::v1::ServerReflectionResponse;

void set_error(ServerReflectionResponse* resp, grpc::StatusCode code, const std::string& msg) {
  resp->mutable_error_response()->set_error_code(int(code));
  resp->mutable_error_response()->set_error_message(msg);
}

// The file and every file it imports (each once), as reflection clients
// expect: they build their own pool from the answer.
void add_file_and_deps(const pb::FileDescriptor* file, std::set<std::string>* seen, ServerReflectionResponse* resp) {
  std::vector<const pb::FileDescriptor*> todo = {file};
  while (!todo.empty()) {
    const pb::FileDescriptor* f = todo.back();
    todo.pop_back();
    if (!seen->insert(f->name()).second) continue;
    pb::FileDescriptorProto proto;
    f->CopyTo(&proto);
    resp->mutable_file_descriptor_response()->add_file_descriptor_proto(proto.SerializeAsString());
    for (int i = 0; i < f->dependency_count(); ++i) todo.push_back(f->dependency(i));
  }
}

}  // namespace

grpc::Status ReflectionV1Service::ServerReflectionInfo(
    grpc::ServerContext*, grpc::ServerReaderWriter<ServerReflectionResponse, ServerReflectionRequest>* stream) {
  const pb::DescriptorPool* pool = pb::DescriptorPool::generated_pool();
  ServerReflectionRequest req;
  while (stream->Read(&req)) {
    ServerReflectionResponse resp;
    resp.set_valid_host(req.host());
    *resp.mutable_original_request() = req;
    std::set<std::string> seen;
    switch (req.message_request_case()) {
      case ServerReflectionRequest::kListServices:
        for (const auto& s : services_) resp.mutable_list_services_response()->add_service()->set_name(s);
        break;
      case ServerReflectionRequest::kFileByFilename:
        if (const pb::FileDescriptor* f = pool->FindFileByName(req.file_by_filename()))
          add_file_and_deps(f, &seen, &resp);
        else
          set_error(&resp, grpc::StatusCode::NOT_FOUND, "file not found");
        break;
      case ServerReflectionRequest::kFileContainingSymbol:
        if (const pb::FileDescriptor* f = pool->FindFileContainingSymbol(req.file_containing_symbol()))
          add_file_and_deps(f, &seen, &resp);
        else
          set_error(&resp, grpc::StatusCode::NOT_FOUND, "symbol not found");
        break;
      case ServerReflectionRequest::kFileContainingExtension: {
        const auto& ext = req.file_containing_extension();
        const pb::Descriptor* type = pool->FindMessageTypeByName(ext.containing_type());
        const pb::FieldDescriptor* field = type ? pool->FindExtensionByNumber(type, ext.extension_number()) : nullptr;
        if (field) add_file_and_deps(field->file(), &seen, &resp);
        else set_error(&resp, grpc::StatusCode::NOT_FOUND, "extension not found");
        break;
      }
      case ServerReflectionRequest::kAllExtensionNumbersOfType: {
        const pb::Descriptor* type = pool->FindMessageTypeByName(req.all_extension_numbers_of_type());
        if (!type) {
          set_error(&resp, grpc::StatusCode::NOT_FOUND, "type not found");
          break;
        }
        std::vector<const pb::FieldDescriptor*> exts;
        pool->FindAllExtensions(type, &exts);
        auto* out = resp.mutable_all_extension_numbers_response();
        out->set_base_type_name(type->full_name());
        for (const auto* e : exts) out->add_extension_number(e->number());
        break;
      }
      default:
        set_error(&resp, grpc::StatusCode::UNIMPLEMENTED, "unknown request");
        break;
    }
    if (!stream->Write(resp)) break;
  }
  return grpc::Status::OK;
}

}  // namespace gdvr::server
