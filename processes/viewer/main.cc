// lanemap-viewer: the live map in a browser (Leaflet page over HTTP on 127.0.0.1), or a finished
// store with --store.
// The process: processes/viewer/viewer_app.h (what it does, its STATUS counters).
//
//   lanemap-viewer --osm roads.osm [--config config/viewer.yaml] [--listen 127.0.0.1] [--port 8765]
//   lanemap-viewer --store DIR --osm roads.osm     browse a finished map store: no LCM at all
#include "processes/viewer/viewer_app.h"

int main(int argc, char** argv) {
  std::vector<char*> args = lanemap::viewer_app::busArguments(argc, argv);  // --store: memq://
  if (args.empty()) return 2;
  lanemap::Process process("viewer");
  lanemap::viewer_app::ViewerFlags flags;
  flags.add(process.cli());
  if (int rc = process.init(static_cast<int>(args.size()), args.data()); rc >= 0) return rc;
  return lanemap::viewer_app::run(process, flags);
}
