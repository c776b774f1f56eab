// Lets an executable count its own heap allocations (STYLE.md, memory: prove "no allocation
// after start"). The object library swf_core_allocation_interposer replaces the allocation
// functions (malloc, calloc, realloc, every operator new) and calls NoteAllocation() on each
// call; the executable supplies the counting policy by defining NoteAllocation() once:
//   tests/support   every thread, while a counting scope is open (unit tests);
//   fsw/app         threads marked real-time (the flight binaries' health_t report).
// Link the objects into executables only, never into a library another program might load.
#pragma once

namespace swf::core {

// Called on every allocation, from the allocating thread, before the memory is obtained. Must
// not allocate and must be safe to call before main and from any thread.
void NoteAllocation();

}  // namespace swf::core
