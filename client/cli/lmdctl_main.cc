// lmdctl: the command-line tool for lmdd.
#include <cstdio>
#include <cstdlib>
#include <map>
#include <new>

#include "client/cli/commands.h"

namespace lmd::cli {
namespace {

constexpr char kUsage[] =
    "usage: lmdctl [--server HOST:PORT] [--json] [--timeout SECONDS] [--token TOKEN]\n"
    "              [--tls-ca PEM [--tls-cert PEM --tls-key PEM] [--tls-server-name NAME]] [--route] <command> [options]\n"
    "commands:\n"
    "  insert --collection C --file POINTS [--id ID] [--robot R]   store a map from a points file\n"
    "  get --collection C --id ID [--out POINTS]                   show (and save) a stored map\n"
    "  delete --collection C --id ID                               delete a stored map\n"
    "  list --collection C                                         list a collection's maps (alias: maps)\n"
    "  collections                                                 list collections\n"
    "  ingest --collection C --log FILE [--robot R]                local maps of a CARMEN log (5 m every 1 m), inserted\n"
    "  ingest --collection C --bag PATH [BAG OPTIONS]              local maps of a bag (MCAP, rosbag2 dir or .db3, ROS 1 .bag)\n"
    "  query --collection C QUERY [--top-k N] [--method M]         stored maps showing the query's place\n"
    "  changes --collection C QUERY [--top-k N] [--method M]       hits with their ranked change masks\n"
    "        (query / changes --mcap OUT.mcap: the answer for Foxglove, Lichtblick or ros2 bag play)\n"
    "  render --collection C QUERY --out FILE.svg                  picture of the top hit and its changes\n"
    "  import-map --collection C --yaml MAP.yaml [--tile M]        a Nav2 map as anchored local maps (tiles of 12 m, half overlapping)\n"
    "  export-map --collection C --out MAP.yaml [--id ID]          anchored maps (or one map) as a Nav2 map (YAML + PGM)\n"
    "  site --collection C --out FILE.svg                          the collection's anchored maps as one site map\n"
    "  anchor --collection C --id ID --pose X,Y,THETA              re-anchor a stored map in the collection's frame\n"
    "  anchor --collection C --file ANCHORS                        ... many: 'ID X Y THETA' lines (m, m, deg)\n"
    "  stats [--collection C]                                      server and collection statistics\n"
    "  cluster                                                     nodes, each collection's copies, in-sync sets and lag\n"
    "  cluster --collection C --copies N                           keep N copies of C (1 to 9) in the cluster\n"
    "  demo [--collection C] [--out DIR]                           store a simulated robot's run, localise another's\n"
    "  backup --dir DIR                                            consistent copy of lmdd's store into DIR (on the server)\n"
    "QUERY is --file POINTS, --log FILE --map K or --bag PATH --map K; M is default, lmd-cor, lmd-cog or bow;\n"
    "BAG OPTIONS: --scan-topic T, --odom-topic T or --frame F (tf frame, e.g. map) choose the scans and poses (default:\n"
    "the only LaserScan topic; tf map, else the only Odometry topic, else tf odom, else scan matching);\n"
    "--scan-matching poses by scan matching; --allow-nan reads NaN ranges as no return; --salvage reads a cut-off file.\n"
    "ingest --anchor stores each map with its first pose in the log's or bag's frame as pose hint (export-map draws them).\n"
    "--exclude ID[,ID...] leaves those stored maps out of query / changes / render hits;\n"
    "--verify N verifies the index's best N hits geometrically (default: the server's, 20; more when lost);\n"
    "--prior X,Y,THETA[,RADIUS] (m, m, deg, m; radius 2) is the query's pose in an anchored collection's frame:\n"
    "only maps near it are matched (--prior-sigma DEG heading uncertainty, 15; --fall-back: a global answer if none\n"
    "matches); --sequence K (with --log / --bag) adds the K maps before --map, --sequence-step maps apart (5), with\n"
    "their relative poses from the route, so that a look-alike place must fit the whole sequence;\n"
    "--length / --step (m) change the local maps built from a log (5 and 1); --heading-drift D (deg per metre)\n"
    "states on each map sent (log, bag or --file with poses) that its poses may turn by up to D per metre (wheel\n"
    "odometry; lmdd then widens the answer's covariance by the bend and is sure only where it cannot break 1 deg;\n"
    "default 0: scan-matched or SLAM poses).\n"
    "--route (in a cluster) sends calls straight to the collection's primary or an in-sync copy, not via --server.\n"
    "--json prints one JSON object per line. Errors: one line on stderr, exit 1 (2: usage);\n"
    "GRPC_VERBOSITY=ERROR adds gRPC's own log lines (lmdctl keeps them off).\n";

using Command = int (*)(const CommandContext&);

const std::map<std::string, Command>& Commands() {
  static const std::map<std::string, Command> commands = {
      {"insert", InsertCommand},   {"get", GetCommand},
      {"delete", DeleteCommand},   {"list", ListMapsCommand},
      {"maps", ListMapsCommand},   {"collections", CollectionsCommand},
      {"stats", StatsCommand},     {"backup", BackupCommand},
      {"cluster", ClusterCommand},
      {"demo", DemoCommand},       {"ingest", IngestCommand},
      {"query", QueryCommand},     {"changes", ChangesCommand},
      {"render", RenderCommand},   {"import-map", ImportMapCommand},
      {"export-map", ExportMapCommand}, {"site", SiteCommand}, {"anchor", AnchorCommand},
  };
  return commands;
}

// --tls-cert and --tls-key go together, and with the --tls-ca that turns
// TLS on: alone, a flag was ignored or read as an empty file name.
Status CheckTlsFlags(const Args& args) {
  if (args.Has("tls-cert") && !args.Has("tls-key")) return Status::InvalidArgument("--tls-cert needs --tls-key");
  if (args.Has("tls-key") && !args.Has("tls-cert")) return Status::InvalidArgument("--tls-key needs --tls-cert");
  for (const char* flag : {"tls-cert", "tls-server-name"}) {
    if (args.Has(flag) && !args.Has("tls-ca")) {
      return Status::InvalidArgument(std::string("--") + flag + " needs --tls-ca (the CA of lmdd's certificate)");
    }
  }
  return Status::Ok();
}

}  // namespace

int Fail(const std::string& message, int code) {
  std::fprintf(stderr, "lmdctl: %s\n", message.c_str());
  return code;
}

int FailCall(const grpc::Status& status) {
  static const char* const kNames[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
                                       "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED",
                                       "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED",
                                       "INTERNAL", "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
  const int code = status.error_code();
  const std::string name = code >= 0 && code <= 16 ? kNames[code] : "UNKNOWN";
  std::string message = status.error_message();
  if (message.empty()) message = "(no message)";
  return Fail(name + ": " + message);
}

std::string Required(const Args& args, const std::string& key) {
  if (!args.Has(key) || args.Get(key).empty()) {
    Fail("missing --" + key + " (see lmdctl --help)", 2);
    return "";
  }
  return args.Get(key);
}

int Main(int argc, char** argv) {
  // gRPC logs failures on stderr itself (E... lines before lmdctl's own):
  // off unless the user sets GRPC_VERBOSITY, so that an error is one line.
  setenv("GRPC_VERBOSITY", "NONE", /*overwrite=*/0);
  Result<Args> args = ParseArgs(argc, argv, 1, {"json", "help", "h", "scan-matching", "allow-nan", "salvage", "anchor", "fall-back", "route"});
  if (!args.ok()) return Fail(args.status().message(), 2);
  if (args->Switch("help") || args->Switch("h") || args->positional.empty()) {
    std::fputs(kUsage, args->positional.empty() && !args->Switch("help") && !args->Switch("h") ? stderr : stdout);
    return args->positional.empty() && !args->Switch("help") && !args->Switch("h") ? 2 : 0;
  }
  const auto command = Commands().find(args->positional.front());
  if (command == Commands().end()) return Fail("unknown command '" + args->positional.front() + "' (see --help)", 2);
  if (args->positional.size() > 1) return Fail("unexpected argument '" + args->positional[1] + "'", 2);
  const Status known = CheckKnownOptions(
      *args, {"server", "timeout", "token", "tls-ca", "tls-cert", "tls-key", "tls-server-name", "collection", "file",
              "id", "robot", "out", "log", "map", "length", "step", "heading-drift", "top-k", "verify", "method",
              "exclude", "dir", "bag", "scan-topic", "odom-topic", "frame", "mcap", "yaml", "tile", "stride",
              "resolution", "prior", "prior-sigma", "sequence", "sequence-step", "copies", "pose"});
  if (!known.ok()) return Fail(known.message(), 2);
  Result<long> timeout = GetPositive(*args, "timeout", 30, 86400);
  if (!timeout.ok()) return Fail(timeout.status().message(), 2);
  const Status tls = CheckTlsFlags(*args);
  if (!tls.ok()) return Fail(tls.message(), 2);

  client::ClientOptions options;
  options.target = args->Get("server", "127.0.0.1:50051");
  options.deadline = std::chrono::seconds(*timeout);
  options.token = args->Get("token");
  options.tls_root_ca_file = args->Get("tls-ca");
  options.tls_cert_file = args->Get("tls-cert");
  options.tls_key_file = args->Get("tls-key");
  options.tls_server_name = args->Get("tls-server-name");
  options.route = args->Switch("route");
  Result<std::unique_ptr<client::LmdClient>> client = client::LmdClient::Create(options);
  if (!client.ok()) return Fail(client.status().message());
  return command->second(CommandContext{**client, *args, args->Switch("json")});
}

}  // namespace lmd::cli

int main(int argc, char** argv) {
  try {
    return lmd::cli::Main(argc, argv);
  } catch (const std::bad_alloc&) {  // e.g. a log that decompresses to gigabytes
    std::fputs("lmdctl: out of memory (is the log or points file that large?)\n", stderr);
    return 1;
  }
}
