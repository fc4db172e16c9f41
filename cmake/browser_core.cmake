# The browser's client core (docs/architecture.md, "Browser build"): the files the WASM module compiles, and
# no others, as absolute paths. Both builds include this list: the native one for browser_core_check (the
# fast guard that they compile and link on their own), the emscripten one (web/CMakeLists.txt) for the module.
get_filename_component(PMSTREAM_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
set(PMSTREAM_BROWSER_CORE
  # the client: the session modes' protocol logic and free-running driver, the HTTP clients over HttpTransport
  src/client/client_session.cpp src/client/client_modes.cpp src/client/free_running_session.cpp
  src/client/sender_driven_client.cpp src/client/sender_plain_client.cpp src/client/view_independent_client.cpp
  src/client/dag_client.cpp src/client/dag_management.cpp src/client/receiver_client.cpp
  src/client/multilevel_client.cpp
  src/client/http_transport.cpp src/client/mesh_buffers.cpp src/client/viewer.cpp src/client/model_version.cpp
  # the browser's viewers: the session modes over messages, the HTTP ones over a transport fed from outside,
  # the receiver's importance from a face-id frame
  src/client/message_session_viewer.cpp src/client/server_greeting.cpp src/client/external_http_transport.cpp
  src/client/receiver_viewer.cpp src/client/multilevel_viewer.cpp src/client/face_id_importance.cpp
  src/client/importance.cpp
  # protocol: messages, framing, split bands and requests, URLs
  src/protocol/base.cpp src/protocol/base64url.cpp src/protocol/client_messages.cpp
  src/protocol/codec_message.cpp src/protocol/framing.cpp src/protocol/open.cpp src/protocol/server_messages.cpp
  src/protocol/split_bands.cpp src/protocol/split_request.cpp src/protocol/stream_mode.cpp src/protocol/url_segment.cpp
  src/protocol/vsplits.cpp src/protocol/wire.cpp
  # multilevel: the loader, its codec and the LOD
  src/multilevel/codec.cpp src/multilevel/level_neighbours.cpp src/multilevel/loader.cpp src/multilevel/mesh.cpp
  # spm: the partial hierarchy, the refinement engine, the split records and their codec
  src/spm/adapt.cpp src/spm/criteria.cpp src/spm/geomorph.cpp src/spm/hierarchy.cpp src/spm/nested_info.cpp
  src/spm/octahedral_normal.cpp src/spm/position_grid.cpp src/spm/quantize.cpp src/spm/selective_mesh.cpp
  src/spm/selective_mesh_audit.cpp src/spm/split_codec.cpp src/spm/split_record.cpp
  src/spm/vertex_hierarchy.cpp src/spm/vertex_id.cpp
  src/common/camera.cpp src/common/portable_math.cpp src/common/prefix_code.cpp src/common/range_coder.cpp
  src/common/recycled_blocks.cpp)
list(TRANSFORM PMSTREAM_BROWSER_CORE PREPEND "${PMSTREAM_ROOT}/")
