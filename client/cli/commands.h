// lmdctl's commands. Each prints its result (human or --json) on stdout and
// returns the exit code: 0 on success, 1 when the call or input failed (one
// line on stderr), 2 on a usage error.
#pragma once

#include <string>

#include <grpcpp/support/status.h>

#include "client/cli/args.h"
#include "client/lmd_client.h"

namespace lmd::cli {

struct CommandContext {
  const client::LmdClient& client;
  const Args& args;
  bool json = false;
};

// Prints "lmdctl: <message>" on stderr; returns `code`.
int Fail(const std::string& message, int code = 1);
// Prints "lmdctl: <CODE>: <message>" for a failed call; returns 1.
int FailCall(const grpc::Status& status);
// The value of a required option, or "" after printing a usage error.
std::string Required(const Args& args, const std::string& key);

int InsertCommand(const CommandContext& ctx);
int GetCommand(const CommandContext& ctx);
int DeleteCommand(const CommandContext& ctx);
int ListMapsCommand(const CommandContext& ctx);
int CollectionsCommand(const CommandContext& ctx);
int StatsCommand(const CommandContext& ctx);
int BackupCommand(const CommandContext& ctx);
int ClusterCommand(const CommandContext& ctx);
int DemoCommand(const CommandContext& ctx);
int IngestCommand(const CommandContext& ctx);
int QueryCommand(const CommandContext& ctx);
int ChangesCommand(const CommandContext& ctx);
int RenderCommand(const CommandContext& ctx);
int ImportMapCommand(const CommandContext& ctx);
int ExportMapCommand(const CommandContext& ctx);
int SiteCommand(const CommandContext& ctx);
int AnchorCommand(const CommandContext& ctx);

}  // namespace lmd::cli
