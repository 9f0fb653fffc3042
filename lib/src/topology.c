/* lib/src/topology.c: boundary extraction and adjacency. */
typedef int vm_topology_placeholder;
