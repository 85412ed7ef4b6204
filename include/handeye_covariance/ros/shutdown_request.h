// A node's last words: Ctrl-C (SIGINT), SIGTERM and a shutdown request over
// XML-RPC (rosnode kill, a second node of the same name) are caught before
// roscpp closes the node's topics, so that the node can still publish (a hold to
// an arm it is moving). Call ros::init with ros::init_options::NoSigintHandler.
// What cannot be caught: SIGKILL, and the master or the network going away.
#pragma once

#include <functional>

namespace handeye {

/// Spins `threads` callback threads until a shutdown is requested (or ROS stops
/// otherwise), then calls `before_shutdown` while topics are open, then shuts ROS down.
void spin_until_shutdown(int threads, const std::function<void()>& before_shutdown);

}  // namespace handeye
