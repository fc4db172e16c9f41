// The multilevel mode's resources (gueziec et al. 1999; docs/protocol.md, "Multilevel over HTTP"):
// GET /models/{m}/{version}/head and GET /models/{m}/{version}/levels/{level}, immutable, one per level,
// coarsest first, and the same under /models/{m}/{version}/compressed/ in the compressed form
// (multilevel/codec.h).
#pragma once
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string_view>

#include "server/http_routes.h"
#include "server/served_multilevel.h"

namespace pms::server {

// `segments` is the URL's path cut at '/', starting with "models", "{m}", without the version (the caller
// has checked it).
HttpAnswer multilevel_route(const ServedMultilevel& model, const HttpRequest& request,
                            std::span<const std::string_view> segments);

// The model's entry in GET /models.
nlohmann::json multilevel_entry(const ServedMultilevel& model);

}  // namespace pms::server
