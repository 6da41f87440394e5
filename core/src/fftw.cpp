// fftw.cpp — loads FFTW on first use and keeps one pair of plans per length (fftw.h).
#include "fftw.h"

#include <dlfcn.h>

#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

namespace manipid::detail {
namespace {

constexpr const char* kLibrary = "libfftw3.so.3";

std::unique_ptr<Fftw> load() {
  // RTLD_LOCAL: FFTW's symbols serve these pointers only. The handle is never closed (plans
  // and arrays outlive any caller).
  void* library = dlopen(kLibrary, RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) return nullptr;
  auto functions = std::make_unique<Fftw>();
  bool complete = true;
#define MANIPID_FFTW_BIND(name)                                            \
  if (void* symbol = dlsym(library, #name)) {                              \
    functions->name = reinterpret_cast<decltype(functions->name)>(symbol); \
  } else {                                                                 \
    complete = false;                                                      \
  }
  MANIPID_FFTW_FUNCTIONS(MANIPID_FFTW_BIND)
#undef MANIPID_FFTW_BIND
  return complete ? std::move(functions) : nullptr;
}

}  // namespace

const Fftw* fftw() {
  // A static's initialisation runs once, under the compiler's lock. Never freed: arrays and
  // plans call through it until the process ends.
  static const Fftw* const loaded = load().release();
  return loaded;
}

const RealTransforms& RealTransforms::of_length(Eigen::Index length) {
  static std::mutex planning;
  // Never freed, nor are the plans: they serve until the process ends (and a map destroyed at
  // exit would leave FFTW's plans unreachable, which LeakSanitizer reports).
  static auto* const made = new std::map<Eigen::Index, std::unique_ptr<RealTransforms>>();
  const std::lock_guard<std::mutex> lock(planning);
  std::unique_ptr<RealTransforms>& slot = (*made)[length];
  if (!slot) {
    const Fftw& f = *fftw();
    // FFTW_ESTIMATE: plans without running trial transforms on the arrays, ~0.7 ms a plan here
    // (FFTW_MEASURE would take tens of milliseconds per length to gain a little per call).
    const FftwArray<double> reals(length);
    const FftwArray<fftw_complex> spectrum(length / 2 + 1);
    const int n = static_cast<int>(length);
    auto transforms = std::unique_ptr<RealTransforms>(new RealTransforms());
    transforms->forward_ = f.fftw_plan_dft_r2c_1d(n, reals.data(), spectrum.data(), FFTW_ESTIMATE);
    transforms->backward_ = f.fftw_plan_dft_c2r_1d(n, spectrum.data(), reals.data(), FFTW_ESTIMATE | FFTW_DESTROY_INPUT);
    if (!transforms->forward_ || !transforms->backward_) throw std::runtime_error("FFTW made no plan for a transform of length " + std::to_string(length));
    slot = std::move(transforms);
  }
  return *slot;
}

void RealTransforms::forward(double* in, fftw_complex* out) const { fftw()->fftw_execute_dft_r2c(forward_, in, out); }

void RealTransforms::backward(fftw_complex* in, double* out) const { fftw()->fftw_execute_dft_c2r(backward_, in, out); }

}  // namespace manipid::detail
