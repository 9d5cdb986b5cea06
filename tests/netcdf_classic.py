"""A reader of classic netCDF files (CDF-1 and CDF-2, the format of Exodus II files such as
Peridigm's gold files), in plain Python for the test checkers: variables by name, as flat lists
of numbers (or text for char variables) with their shape. Record variables are read over all
records. Big-endian, as the format defines.
"""
import struct

TYPES = {1: ("b", 1), 2: ("c", 1), 3: ("h", 2), 4: ("i", 4), 5: ("f", 4), 6: ("d", 8)}


class NetcdfClassic:
    def __init__(self, path):
        with open(path, "rb") as f:
            self.data = f.read()
        if self.data[:3] != b"CDF" or self.data[3] not in (1, 2):
            raise ValueError(f"{path} is not a classic netCDF file")
        self.offset_size = 4 if self.data[3] == 1 else 8
        self.pos = 4
        self.numrecs = self.int()
        self.dims = [(name, size) for name, size in self.list(0x0A, lambda: (self.name(), self.int()))]
        self.list(0x0C, self.attribute)
        self.vars = {}
        for name, dimids, typ, vsize, begin in self.list(0x0B, self.variable):
            self.vars[name] = (dimids, typ, vsize, begin)
        self.record_size = sum(v[2] for v in self.vars.values() if self.is_record(v))
        records = [v for v in self.vars.values() if self.is_record(v)]
        if len(records) == 1:  # a single record variable is not padded to 4 bytes
            d, typ, _, _ = records[0]
            self.record_size = TYPES[typ][1] * self.count(d[1:])

    def int(self):
        v = struct.unpack(">i", self.data[self.pos:self.pos + 4])[0]
        self.pos += 4
        return v

    def offset(self):
        fmt = ">i" if self.offset_size == 4 else ">q"
        v = struct.unpack(fmt, self.data[self.pos:self.pos + self.offset_size])[0]
        self.pos += self.offset_size
        return v

    def name(self):
        n = self.int()
        s = self.data[self.pos:self.pos + n].decode()
        self.pos += (n + 3) // 4 * 4
        return s

    def list(self, tag, item):
        t, n = self.int(), self.int()
        if t == 0:
            return []
        if t != tag:
            raise ValueError(f"netCDF header: tag {t} where {tag} was expected")
        return [item() for _ in range(n)]

    def attribute(self):
        name, typ, n = self.name(), self.int(), self.int()
        self.pos += (TYPES[typ][1] * n + 3) // 4 * 4
        return name

    def variable(self):
        name = self.name()
        dimids = [self.int() for _ in range(self.int())]
        self.list(0x0C, self.attribute)
        typ, vsize, begin = self.int(), self.int(), self.offset()
        return name, dimids, typ, vsize, begin

    def is_record(self, v):
        return bool(v[0]) and self.dims[v[0][0]][1] == 0

    def count(self, dimids):
        n = 1
        for d in dimids:
            n *= self.dims[d][1]
        return n

    def shape(self, name):
        dimids = self.vars[name][0]
        return [self.numrecs if self.dims[d][1] == 0 else self.dims[d][1] for d in dimids]

    def __contains__(self, name):
        return name in self.vars

    def values(self, name):
        """The variable's values, flat in C order (records first)."""
        dimids, typ, _, begin = self.vars[name]
        code, size = TYPES[typ]
        v = self.vars[name]
        if self.is_record(v):
            n = self.count(dimids[1:])
            out = []
            for r in range(self.numrecs):
                at = begin + r * self.record_size
                out += self.unpack(code, n, at)
            return out
        return self.unpack(code, self.count(dimids), begin)

    def unpack(self, code, n, at):
        if code == "c":
            return list(self.data[at:at + n])
        size = TYPES[[k for k, t in TYPES.items() if t[0] == code][0]][1]
        return list(struct.unpack(f">{n}{code}", self.data[at:at + n * size]))

    def rows(self, name):
        """The variable as a list of its last-dimension rows."""
        vals, shape = self.values(name), self.shape(name)
        w = shape[-1]
        return [vals[i:i + w] for i in range(0, len(vals), w)]

    def strings(self, name):
        """A char variable's rows as text (Exodus' name lists)."""
        return [bytes(b for b in row if b != 0).decode().strip() for row in self.rows(name)]
