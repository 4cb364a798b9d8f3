// Error.cc - anchors the exception vtables in the library.
#include <fluidsurf/Error.h>
