// Device addresses as uvec2 (x: low 32 bits): buffer references are built
// from them with GL_EXT_buffer_reference_uvec2, so no kernel needs 64-bit
// integers (shaderInt64). The C push-constant and parameter structs keep
// uint64_t fields: same size, alignment and byte order on little-endian hosts.
#ifndef PB_ADDRESS_GLSL
#define PB_ADDRESS_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#define pb_addr uvec2

bool addr_null(pb_addr a)
{
    return (a.x | a.y) == 0u;
}

#endif
