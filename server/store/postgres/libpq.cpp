// libpq.cpp — loads libpq on first use (libpq.h).
#include "store/postgres/libpq.h"

#include "store/store.h"

#include <dlfcn.h>

#include <string>

namespace manipid::server::store::postgres {
namespace {

constexpr const char* kLibrary = "libpq.so.5";

template <typename Function>
void bind(void* library, const char* name, Function& slot) {
  void* symbol = dlsym(library, name);
  if (symbol == nullptr) throw StoreError(std::string(kLibrary) + " has no " + name + " (libpq older than PostgreSQL 15's?)");
  slot = reinterpret_cast<Function>(symbol);
}

Libpq load() {
  // RTLD_LOCAL: libpq's symbols serve these pointers only. The handle is never closed.
  void* library = dlopen(kLibrary, RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) {
    const char* why = dlerror();
    throw StoreError(std::string("PostgreSQL needs libpq (Debian package libpq5): ") + (why ? why : kLibrary));
  }
  Libpq functions;
#define MANIPID_LIBPQ_BIND(name) bind(library, #name, functions.name);
  MANIPID_LIBPQ_FUNCTIONS(MANIPID_LIBPQ_BIND)
#undef MANIPID_LIBPQ_BIND
  return functions;
}

}  // namespace

const Libpq& libpq() {
  // A static's initialisation runs once, under the compiler's lock; if it throws, the next call
  // runs it again.
  static const Libpq loaded = load();
  return loaded;
}

}  // namespace manipid::server::store::postgres
