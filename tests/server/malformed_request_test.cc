// Request bytes that do not parse as their method's message get
// INVALID_ARGUMENT naming the message (server/parse_errors.h), unary or
// streamed (server/stream_insert.h), counted as calls with errors, and lmdd
// serves the next call. The calls are made with gRPC's generic stub, which
// sends bytes as they are.
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <gtest/gtest.h>

#include "proto/metadata_keys.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

// A length-delimited field 1 whose length runs past the end of the message.
const std::string kNotAMessage("\x0a\xff\xff\xff\xff\x0f", 6);

grpc::ByteBuffer Bytes(const std::string& bytes) {
  grpc::Slice slice(bytes);
  return grpc::ByteBuffer(&slice, 1);
}

// Waits for the completion queue's next event and says whether it went well.
bool Next(grpc::CompletionQueue* queue) {
  void* tag = nullptr;
  bool ok = false;
  return queue->Next(&tag, &ok) && ok;
}

grpc::Status UnaryBytes(const std::string& address, const std::string& method, const std::string& bytes) {
  grpc::GenericStub stub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext context;
  grpc::CompletionQueue queue;
  auto call = stub.PrepareUnaryCall(&context, method, Bytes(bytes), &queue);
  call->StartCall();
  grpc::ByteBuffer response;
  grpc::Status status;
  call->Finish(&response, &status, reinterpret_cast<void*>(1));
  Next(&queue);
  queue.Shutdown();
  while (Next(&queue)) {
  }
  return status;
}

// Streams `messages` to StreamInsertMaps as they are; the call's status and
// its trailing count of stored maps.
grpc::Status StreamBytes(const std::string& address, const std::vector<std::string>& messages,
                         std::string* stored_maps) {
  grpc::GenericStub stub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext context;
  grpc::CompletionQueue queue;
  auto call = stub.PrepareCall(&context, "/lmd.v1.LmdService/StreamInsertMaps", &queue);
  call->StartCall(reinterpret_cast<void*>(1));
  Next(&queue);
  for (const std::string& m : messages) {
    call->Write(Bytes(m), reinterpret_cast<void*>(2));
    if (!Next(&queue)) break;  // the server ended the call
  }
  call->WritesDone(reinterpret_cast<void*>(3));
  Next(&queue);
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(4));
  Next(&queue);
  queue.Shutdown();
  while (Next(&queue)) {
  }
  const auto& trailers = context.GetServerTrailingMetadata();
  const auto found = trailers.find(kStoredMapsMetadata);
  *stored_maps = found == trailers.end() ? "" : std::string(found->second.data(), found->second.size());
  return status;
}

TEST(MalformedRequestTest, BytesThatAreNoRequestAreNamedAsSuch) {
  TempDir dir;
  TestServer server(dir.path());
  const grpc::Status retrieve = UnaryBytes(server.address(), "/lmd.v1.LmdService/Retrieve", kNotAMessage);
  EXPECT_EQ(retrieve.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(retrieve.error_message(), "the request does not parse as lmd.v1.RetrieveRequest");
  const grpc::Status insert = UnaryBytes(server.address(), "/lmd.v1.LmdService/InsertMaps", kNotAMessage);
  EXPECT_EQ(insert.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(insert.error_message(), "the request does not parse as lmd.v1.InsertMapsRequest");
  // A method lmdd does not have stays unimplemented.
  EXPECT_EQ(UnaryBytes(server.address(), "/lmd.v1.LmdService/NoSuchMethod", "").error_code(),
            grpc::StatusCode::UNIMPLEMENTED);
  // The same bytes, parsed, are a request again: an empty ListCollections.
  EXPECT_TRUE(UnaryBytes(server.address(), "/lmd.v1.LmdService/ListCollections", "").ok());
  // No handler saw the calls that did not parse; they count as calls with errors all the same.
  v1::StatsResponse stats;
  ASSERT_TRUE(server.client().Stats(v1::StatsRequest(), &stats).ok());
  size_t counted = 0;
  for (const v1::MethodStats& m : stats.methods()) {
    if (m.method() != "Retrieve" && m.method() != "InsertMaps") continue;
    ++counted;
    EXPECT_EQ(m.calls(), 1u) << m.method();
    EXPECT_EQ(m.errors(), 1u) << m.method();
  }
  EXPECT_EQ(counted, 2u);
}

TEST(MalformedRequestTest, AStreamEndsAtAMessageThatDoesNotParseAndKeepsTheMapsBeforeIt) {
  TempDir dir;
  TestServer server(dir.path());
  const std::string first = OneMapRequest("fleet", "s0", SquareRoomMap()).maps(0).SerializeAsString();
  const std::string third = OneMapRequest("fleet", "s2", SquareRoomMap()).maps(0).SerializeAsString();
  std::string stored;
  const grpc::Status status = StreamBytes(server.address(), {first, kNotAMessage, third}, &stored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "message 1 of the stream does not parse as lmd.v1.InsertMapRequest (the stream's first 1 maps are stored)");
  EXPECT_EQ(stored, "1");
  v1::GetMapRequest get;
  get.set_collection("fleet");
  get.set_map_id("s0");
  v1::GetMapResponse got;
  EXPECT_TRUE(server.client().GetMap(get, &got).ok());
  get.set_map_id("s2");
  EXPECT_EQ(server.client().GetMap(get, &got).error_code(), grpc::StatusCode::NOT_FOUND);
}

}  // namespace
}  // namespace lmd::testing
