#include "handeye_covariance/ros/shutdown_request.h"

#include <ros/ros.h>
#include <ros/xmlrpc_manager.h>

#include <atomic>
#include <signal.h>

#include <csignal>

namespace handeye {
namespace {

std::atomic<bool> requested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler stores a lock-free flag, nothing else");

void on_signal(int) { requested = true; }

// roscpp's own "shutdown" XML-RPC method, except that it asks this loop to stop
// instead of closing the topics at once.
void on_shutdown_call(XmlRpc::XmlRpcValue& params, XmlRpc::XmlRpcValue& result) {
  if (params.getType() == XmlRpc::XmlRpcValue::TypeArray && params.size() > 1) {
    const std::string reason = params[1];
    ROS_WARN("Shutdown request received: [%s]", reason.c_str());
    requested = true;
  }
  result = ros::xmlrpc::responseInt(1, "", 0);
}

}  // namespace

void spin_until_shutdown(int threads, const std::function<void()>& before_shutdown) {
  // Once: a second Ctrl-C ends the process at once (SA_RESETHAND restores the default).
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  ros::XMLRPCManager::instance()->unbind("shutdown");
  ros::XMLRPCManager::instance()->bind("shutdown", on_shutdown_call);
  ros::AsyncSpinner spinner(threads);
  spinner.start();
  while (!requested && ros::ok()) ros::WallDuration(0.01).sleep();
  if (ros::ok()) before_shutdown();
  spinner.stop();
  ros::shutdown();
}

}  // namespace handeye
