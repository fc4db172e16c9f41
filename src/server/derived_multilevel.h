// A .pms model's multilevel mesh (gueziec et al. 1999), derived when a client first asks for it: the
// levels `pmstream multilevel build` makes from the builder's collapses, here from the collapses the
// model's hierarchy records (multilevel/build.h, collapses_of).
#pragma once
#include <memory>
#include <string>

#include "io/mesh.h"
#include "server/served_multilevel.h"
#include "spm/hierarchy.h"

namespace pms::server {

// The model refined completely, numbered as the builder's cleaned input was (leaf_vertex): the mesh the
// collapses of its hierarchy apply to. pms::Error for a model whose leaves do not number that mesh.
Mesh full_resolution_mesh(const ModelData& model);

// Every level (none merged), cut into the resources of /models/{name}/{version}.
std::unique_ptr<ServedMultilevel> derive_multilevel(const std::string& name, const std::string& path,
                                                    const std::string& version, const ModelData& model);

}  // namespace pms::server
