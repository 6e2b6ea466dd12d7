// The JSON text of the graphs in planner/experiments/graphs/, compiled into the executable so that
// `corridor experiment analytical --graph simple` works from any directory.
#pragma once

#include <string_view>

namespace corridor::planner {

// Empty for an unknown name.
std::string_view builtin_graph_json(std::string_view name);

}  // namespace corridor::planner
