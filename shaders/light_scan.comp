// Deep light map, compressed on the GPU: the columns' node counts (columns[base + 2 c + 1],
// from light_compress.comp's PASS 1) into the index of each column's first node
// (columns[base + 2 c]), the columns in order, and the total after the last column
// (columns[base + 2 n]).  One work group:
// each invocation sums a run of columns, the runs' sums are scanned in shared memory, and each
// invocation then numbers its own run.

#include "bindings.h"

layout(local_size_x = 1024) in;

layout(std430, binding = BIND_SCAN_BUF_COLUMNS) buffer light_columns {
    uint columns[];
};

uniform uint column_count;
uniform uint base; // the part's first word in columns[]

shared uint partial[1024];

void main()
{
    uint id = gl_LocalInvocationID.x;
    uint run = (column_count + 1023u) / 1024u;
    uint start = min(id * run, column_count), end = min(start + run, column_count);
    uint sum = 0u;
    for (uint c = start; c < end; c++)
        sum += columns[base + 2u * c + 1u];
    partial[id] = sum;
    barrier();
    for (uint offset = 1u; offset < 1024u; offset <<= 1) {
        uint add = id >= offset ? partial[id - offset] : 0u;
        barrier();
        partial[id] += add;
        barrier();
    }
    uint first = id > 0u ? partial[id - 1u] : 0u;
    for (uint c = start; c < end; c++) {
        columns[base + 2u * c] = first;
        first += columns[base + 2u * c + 1u];
    }
    if (id == 1023u)
        columns[base + 2u * column_count] = partial[1023];
}
