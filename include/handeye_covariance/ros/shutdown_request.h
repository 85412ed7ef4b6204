// A node's last words: Ctrl-C (SIGINT), SIGTERM and a shutdown request over
// XML-RPC (rosnode kill, a second node of the same name) are caught before
// roscpp closes the node's topics, so that the node can still publish (a hold to
// an arm it is moving). Call ros::init with ros::init_options::NoSigintHandler.
// A second Ctrl-C ends the process at once. What cannot be caught: SIGKILL, and the
// master or the network going away; when a second node takes this one's name, the
// master drops this one's topics too, so its hold is a best effort.
#pragma once

#include <functional>

namespace handeye {

/// Spins `threads` callback threads until a shutdown is requested (or ROS stops
/// otherwise), then calls `before_shutdown` while topics are open, then shuts ROS down.
void spin_until_shutdown(int threads, const std::function<void()>& before_shutdown);

}  // namespace handeye
