// VdbGrids.cc - every grid of a .vdb in memory: our walk (VdbCheck) first, then OpenVDB's reader
// on the walked copy, straight from memory (no delayed loading: that would map a temporary copy
// of the file and decode each leaf later, wherever it is first touched).
#include "io/VdbGrids.h"

#include "io/VdbCheck.h"

#include <fluidsurf/Error.h>

#include <openvdb/io/Stream.h>

#include <istream>
#include <streambuf>

namespace fluidsurf {
namespace io_internal {

namespace {

/// Read-only streambuf over a memory block (no copy).
struct MemoryBuf : std::streambuf
{
    MemoryBuf(const uint8_t* d, size_t n)
    {
        char* p = const_cast<char*>(reinterpret_cast<const char*>(d));
        setg(p, p, p + n);
    }
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override
    {
        char* target = (dir == std::ios_base::beg   ? eback()
                        : dir == std::ios_base::cur ? gptr()
                                                    : egptr()) +
                       off;
        if (target < eback() || target > egptr()) return pos_type(off_type(-1));
        setg(eback(), target, egptr());
        return pos_type(target - eback());
    }
    pos_type seekpos(pos_type pos, std::ios_base::openmode m) override
    {
        return seekoff(off_type(pos), std::ios_base::beg, m);
    }
};

std::string shortened(const std::string& s)
{
    return s.size() > 200 ? s.substr(0, 200) + "..." : s;
}

/// OpenVDB's reading of checked bytes.
openvdb::GridPtrVecPtr parseVdb(const CheckedVdb& checked, const std::string& src,
                                std::vector<std::string>* skipped)
{
    if (skipped) *skipped = checked.skipped;
    try {
        MemoryBuf buf(checked.bytes.data(), checked.bytes.size());
        std::istream stream(&buf);
        stream.exceptions(std::ios::failbit | std::ios::badbit | std::ios::eofbit);
        openvdb::io::Stream vdb(stream, /*delayLoad=*/false);
        return vdb.getGrids();
    } catch (const std::ios_base::failure&) {
        throw InputError(src + ": VDB data ends early (truncated file?)");
    } catch (const std::bad_alloc&) {
        throw InputError(src + ": corrupt VDB (a size field asks for more memory than available)");
    } catch (const std::exception& e) {
        throw InputError(src + ": cannot read VDB: " + shortened(e.what()));
    }
}

} // namespace

openvdb::GridPtrVecPtr readVdbGrids(const uint8_t* data, size_t size, const std::string& src,
                                    std::vector<std::string>* skipped)
{
    openvdb::initialize();
    return parseVdb(checkVdb(data, size, src), src, skipped);
}

openvdb::GridPtrVecPtr readVdbGrids(std::vector<uint8_t>&& file, const std::string& src,
                                    std::vector<std::string>* skipped)
{
    openvdb::initialize();
    CheckedVdb checked = checkVdb(file.data(), file.size(), src);
    std::vector<uint8_t>().swap(file);
    return parseVdb(checked, src, skipped);
}

} // namespace io_internal
} // namespace fluidsurf
