#include "client/cli/anchored_maps.h"

#include "proto/convert.h"

namespace lmd::cli {

grpc::Status ReadAnchoredMaps(const client::LmdClient& client, const std::string& collection, bool with_derived,
                              AnchoredMaps* out) {
  std::vector<std::string> ids;
  v1::ListMapsRequest list;
  list.set_collection(collection);
  do {
    v1::ListMapsResponse page;
    const grpc::Status status = client.ListMaps(list, &page);
    if (!status.ok()) return status;
    for (const v1::MapMetadata& meta : page.maps()) {
      // A pose hint is an anchor (lmdd copies it into `anchor` at insert).
      const bool derived = meta.has_anchor() && meta.anchor().derived();
      if ((!meta.has_anchor() && !meta.has_pose_hint()) || (derived && !with_derived)) continue;
      ids.push_back(meta.map_id());
      out->anchors.push_back(FromProto(meta.has_anchor() ? meta.anchor().pose() : meta.pose_hint()));
      out->derived += derived;
    }
    list.set_page_token(page.next_page_token());
  } while (!list.page_token().empty());
  for (const std::string& id : ids) {
    v1::GetMapRequest get;
    get.set_collection(collection);
    get.set_map_id(id);
    v1::GetMapResponse response;
    const grpc::Status status = client.GetMap(get, &response);
    if (!status.ok()) return status;
    out->maps.push_back(FromProto(response.map().map()));
  }
  return grpc::Status::OK;
}

}  // namespace lmd::cli
