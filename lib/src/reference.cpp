#include "reference.h"

#include "ssgi/error.h"

namespace ssgi::detail {

RayHits trace_reference(const GBuffer&, const GiSettings&, const Environment&) {
  throw Error(ErrorKind::kInternal, {}, "the Embree reference is not built yet");
}

}  // namespace ssgi::detail
