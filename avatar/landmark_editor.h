// `retarget avatar landmarks`: a web page to check and correct an avatar's landmarks by eye, for a
// person who has never seen a vertex index. The avatar (left) and the human face (right) are
// drawn side by side, front or side view, each landmark a labelled dot on both: the human's dot of
// the same name shows what "mouth_left" means. Select a landmark (in the list or by its dot),
// click (or drag its dot) on the avatar: the vertex under the cursor takes it. Landmarks the human
// has and the avatar lacks are added the same way; any can be removed; the last changes undone.
// Save rewrites rig.yaml's `landmarks:` section atomically and nothing else (see
// write_rig_landmarks).
//
// Pages (embedded in the binary from avatar/web/; no request path reaches the file system):
//   GET /                        the editor page          GET /static/<asset>   its script and style
// The API (header "Authorization: Bearer <token>", the token printed in the page's address as
// #token=...; 401 without it, 403 for another one). Bodies are JSON objects (POSTs must say
// Content-Type: application/json, 415 otherwise, so that no other web site can post here):
//   GET  /api/state                        -> the state below
//   GET  /img/<avatar|human>/<front|side>.png   the plain renders the dots are drawn over
//   POST /api/place  {"name", "view", "x", "y"} -> the state, with "picked": vertex
//        x, y: the click in the picture's pixels (x right, y down, pixel (i, j) spans i..i+1);
//        404 for a name neither the human nor the avatar has, 422 for a click beside the head
//   POST /api/remove {"name"}              -> the state (404 if the avatar has no such landmark)
//   POST /api/undo                         -> the state (409 with nothing to undo)
//   POST /api/save                         -> the state, with "saved": the rig.yaml path
// The state: {"rig", "human", "rig_yaml", "size": [width, height], "views": ["front", "side"],
//   "landmarks": [{"name", "avatar": null | {"vertex", "origin": "proposed" | "hand-set" |
//   "rig.yaml", "confidence": 0..1 | null, "how", "pixels": {"front": [x, y, visible], "side":
//   [...]}}, "human": null | {"pixels": {...}}}], "can_undo", "last_change", "unsaved"}.
// Errors are {"error": message} with a 4xx status; a malformed body gets 400 naming the field.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "geometry/mesh.h"
#include "render/render.h"
#include "web/connection_limits.h"

namespace retarget {

// Which vertex of a drawn mesh lies under a point of its picture: the mesh is projected with the
// picture's own camera (project_to_image) and its depth rasterised once, so that a click finds
// the surface the user sees, never a vertex hidden behind it.
class VertexPicker {
 public:
  // vertices: #V x 3 as drawn (mesh units, +y up, +z towards the viewer); options: the picture's
  // render options (options.frame is set to the vertices' box when absent, as render() does).
  VertexPicker(const Mesh& topology, const Positions& vertices, RenderOptions options);

  // The vertex a click at `pixel` (picture pixels, x right, y down, the centre of pixel (i, j) at
  // i + 0.5, j + 0.5) means: of the visible vertices within radius_px of it, the nearest on the
  // picture; with none that close, the nearest corner of the frontmost triangle under the click.
  // -1 when no triangle lies under the click (the background).
  int pick(const Eigen::Vector2d& pixel, double radius_px) const;

  // Where vertex v lands in the picture (pixels, as above) and whether it is seen (not hidden
  // behind the surface in front of it).
  Eigen::Vector2d pixel(int v) const { return projected_.row(v).head<2>().transpose(); }
  bool visible(int v) const { return visible_[static_cast<size_t>(v)]; }
  const RenderOptions& options() const { return options_; }

 private:
  // The depth of the frontmost triangle under `pixel` (-inf for none) and that triangle.
  double surface_depth(const Eigen::Vector2d& pixel, int* triangle) const;

  Triangles triangles_;
  RenderOptions options_;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> projected_;  // #V x (x, y, depth)
  std::vector<bool> visible_;                                            // #V
  // The triangles whose picture touches each kTile x kTile pixel tile, row-major tiles.
  static constexpr int kTile = 16;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<std::vector<int>> tiles_;
};

// Rewrites the top-level `landmarks:` section of `rig_yaml` (name -> vertex index into the
// neutral) and nothing else: every other line stays as it was, comments included. A landmark
// whose vertex is unchanged keeps its line's comment (avatar init's confidence and origin);
// `comments` gives the comment of others (by name; without one, none). Without a `landmarks:`
// key the section is added before `eyes:` (or at the end). A rig.yaml whose top level is not a
// block map ({...} on one line) is written anew from its parsed content: its comments are lost.
// Written atomically (core/atomic_file.h): a reader sees the old file or the new one. Throws
// retarget::Error naming the file when it cannot be read, is not a YAML map, or cannot be
// written.
void write_rig_landmarks(const std::string& rig_yaml, const std::map<std::string, int>& landmarks,
                         const std::map<std::string, std::string>& comments = {});

struct LandmarkEditorOptions {
  std::string host = "127.0.0.1";  // the address to listen on; only loopback unless asked
  int port = 0;                    // 0 = any free port; 0..65535
  std::string token;               // the page's token (>= 8 characters); empty = random
  int view_size = 560;             // pixels, width and height of each picture; 128..2048
  double pick_radius_px = 8;       // how far from a click a vertex may be taken, pixels; 1..64
  size_t max_body_bytes = 4096;    // larger request bodies get 413; 64..1 MiB
  int threads = 16;                // request threads; 1..64
  // Deadlines, keep-alive, the per-client cap (by default half the threads: 8 of the 16, more
  // than the 6 connections a browser opens), header limits: the annotation tool's guards
  // (web/guarded_http_server.h, connection_limits.h).
  ConnectionLimits connections;

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "landmarks") const;
};

class LandmarkEditorServer {
 public:
  // rig_folder: a rig folder (or its rig.yaml) as `retarget avatar init` writes it; its
  // proposals.yaml, when present, gives each proposal's confidence and the face's frame (the
  // avatar is drawn upright in it). face_model_yaml: the human face model whose landmarks name
  // the points (geometry/face_model.h). Loads both and prepares the routes; throws
  // retarget::Error for invalid options, a rig that does not load, a rig.yaml other than a YAML
  // map, or a face model that does not load.
  LandmarkEditorServer(const std::string& rig_folder, const std::string& face_model_yaml,
                       const LandmarkEditorOptions& options);
  ~LandmarkEditorServer();
  LandmarkEditorServer(const LandmarkEditorServer&) = delete;
  LandmarkEditorServer& operator=(const LandmarkEditorServer&) = delete;

  // Binds options.host:options.port and returns the port (the chosen one for port 0). Throws
  // retarget::Error naming the address when it cannot bind.
  int bind();
  // Serves until stop() (from another thread). bind() first.
  void run();
  void stop();

  int port() const;
  const std::string& token() const;
  // "http://127.0.0.1:8080"; the page's address is base_url() + "/#token=" + token().
  std::string base_url() const;
  std::string page_url() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace retarget
