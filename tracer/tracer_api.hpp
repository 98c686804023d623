// What the tracer's shared library exports (tracer/CMakeLists.txt): everything else in it
// is hidden, so that link-time optimisation may treat it as the library's own, inline a
// function called once and drop its body, as it would in a program.
#pragma once

#define TESSERA_TRACER_API [[gnu::visibility("default")]]
