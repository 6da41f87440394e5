// http_endpoint_loader.cpp — finds and loads manipid-http.so for `manipid serve` (http_endpoint.h).
#include "manipid/api/http_endpoint.h"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <stdexcept>
#include <string>
#include <vector>

namespace manipid::api {
namespace {

using OpenEndpoint = HttpEndpoint* (*)(Service*, const HttpSettings*, std::string*);

/// The directory of the running executable (/proc/self/exe), or empty.
std::string executable_directory() {
  std::vector<char> path(PATH_MAX + 1);
  const ssize_t length = readlink("/proc/self/exe", path.data(), path.size() - 1);
  if (length <= 0) return {};
  const std::string file(path.data(), static_cast<std::size_t>(length));
  const std::size_t slash = file.rfind('/');
  return slash == std::string::npos ? std::string() : file.substr(0, slash);
}

/// The entry point of the first module that loads, or a message naming every place tried. Only
/// the places next to the executable: never a path from the environment or a request.
OpenEndpoint load(std::string& failure) {
  const std::string directory = executable_directory();
  if (directory.empty()) {
    failure = "cannot find the executable's directory (/proc/self/exe) to load " + std::string(http_module_name);
    return nullptr;
  }
  for (const std::string& candidate :
       {directory + "/" + http_module_name, directory + "/../lib/manipid/" + http_module_name}) {
    // RTLD_NOW: a module whose symbols the executable does not define (another build) fails
    // here, by name, not at its first request. RTLD_LOCAL: its symbols serve this call only.
    // Never closed: the endpoint's code lives in it until the process ends.
    void* module = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (module == nullptr) {
      const char* why = dlerror();
      failure += (failure.empty() ? "" : "; ") + std::string(why ? why : candidate + ": not loadable");
      continue;
    }
    const auto* interface = static_cast<const int*>(dlsym(module, "manipid_http_module_interface"));
    void* entry = dlsym(module, "manipid_open_http_endpoint");
    if (interface != nullptr && *interface == http_module_interface && entry != nullptr) {
      return reinterpret_cast<OpenEndpoint>(entry);
    }
    failure += (failure.empty() ? "" : "; ") + candidate + ": built with another manipid (its interface differs)";
  }
  return nullptr;
}

/// The module's entry point, loaded on the first call; the same failure, by name, on every call.
OpenEndpoint entry_point() {
  static std::string failure;
  static const OpenEndpoint entry = load(failure);
  if (entry == nullptr) throw std::runtime_error("cannot load the HTTP module " + std::string(http_module_name) + ": " + failure);
  return entry;
}

}  // namespace

void load_http_module() { entry_point(); }

std::unique_ptr<HttpEndpoint> open_http_endpoint(Service& service, const HttpSettings& settings) {
  const OpenEndpoint entry = entry_point();
  std::string error;
  HttpEndpoint* endpoint = entry(&service, &settings, &error);
  if (endpoint == nullptr) throw std::runtime_error("cannot start the HTTP server: " + error);
  return std::unique_ptr<HttpEndpoint>(endpoint);
}

}  // namespace manipid::api
