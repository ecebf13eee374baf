"""CSV files as data recorded elsewhere may come (headers and units right or wrong, numbers,
text, gaps, time columns uniform or not, other encodings, damaged bytes), with the options of
``fsi-lab import``: exit 0 with a run file fsi-lab reads back, or exit 2 with one message naming
the file or the option and nothing written; never a traceback or a hang."""

import math

from fuzzkit import FUZZ, check_command, floats, number_texts, tally, texts
from hypothesis import given, settings
from hypothesis import strategies as st

from fsi_lab.runfile import read_run

CASES = 400
GOOD_NAMES = ["tip", "base", "drive", "tip_velocity", "x-2"]
BAD_NAMES = ["a b", "x/y", "", "1st", "\u00e9", "Time", "tip"]
GOOD_UNITS = ["m", "m/s", "m/s^2", "g", "V"]
BAD_UNITS = ["s", "mm/s", "", "[m]", "m/s/s"]


def rare(draw) -> bool:
    """True in about one case in ten (hypothesis favours 0, so 7 marks the rare case)."""
    return draw(st.integers(0, 9)) == 7


@st.composite
def headers(draw):
    names = draw(st.permutations(GOOD_NAMES))[:draw(st.integers(1, 3))]
    cells = [f"{name} [{draw(st.sampled_from(GOOD_UNITS))}]" for name in names]
    if draw(st.booleans()):
        cells.insert(draw(st.integers(0, len(cells))), "time [s]")
    if rare(draw):
        cells[draw(st.integers(0, len(cells) - 1))] = draw(st.one_of(
            texts, st.builds(lambda n, u: f"{n} [{u}]", st.sampled_from(BAD_NAMES + GOOD_NAMES),
                             st.sampled_from(BAD_UNITS))))
    if rare(draw):
        cells = cells[:draw(st.integers(0, len(cells)))]
    return cells


@st.composite
def csv_files(draw):
    header = draw(headers())
    width = max(1, len(header))
    rows = draw(st.integers(0, 3)) if rare(draw) else draw(st.integers(10, 40))
    time_step = draw(st.sampled_from([5e-324, 1e-300, 1e300, -1e-3, 0.0])) if rare(draw) \
        else draw(st.sampled_from([1e-3, 1e-4, 0.1]))
    jitter = draw(st.sampled_from([1e-6, 0.1])) if rare(draw) else 0.0
    start = draw(st.sampled_from([-1.0, 2e9])) if rare(draw) else draw(st.sampled_from([0, 2.5]))
    scale = draw(st.sampled_from([1e-3, 1e308])) if rare(draw) else 1.0
    lines = [",".join(header)]
    odd_row = draw(st.integers(0, rows)) if rare(draw) else -1  # one row of another width
    junk = (draw(st.integers(0, rows)), draw(st.integers(0, width - 1))) if rare(draw) else None
    for i in range(rows):
        cells = []
        for column in range(width + (draw(st.sampled_from([1, -1])) if i == odd_row else 0)):
            if (i, column) == junk:
                cells.append(draw(st.one_of(number_texts, texts)))
            elif column < len(header) and header[column] == "time [s]":
                cells.append(repr(start + i * time_step * (1 + jitter * (i % 3))))
            else:
                cells.append(repr(math.sin(i + column) * scale))
        lines.append(",".join(cells))
    text = draw(st.sampled_from(["\n", "\r\n"])).join(lines)
    encoding = draw(st.sampled_from(["utf-16", "utf-8-sig"])) if rare(draw) else "utf-8"
    data = text.encode(encoding, errors="surrogatepass")
    if rare(draw):  # damaged bytes
        data = bytearray(data)
        for _ in range(draw(st.integers(1, 4))):
            if data:
                data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
        data = bytes(data)
    return header, data


@st.composite
def options(draw, header):
    args = []
    if draw(st.integers(0, 3)) != 3:
        rate = draw(st.one_of(st.sampled_from([1000.0, 1000.0, 1e-3, 1e9]), floats))
        args += [f"--rate={rate!r}"] if not rare(draw) else ["--rate", repr(rate)]
    names = [cell.split(" [")[0] for cell in header] + ["nope"]
    if draw(st.integers(0, 3)) == 3:
        args += ["--reference", draw(st.sampled_from(names))]
    if draw(st.integers(0, 3)) == 3:
        value = draw(st.one_of(st.sampled_from(["0.0011", "0", "-1", "2", "x"]), number_texts))
        args += ["--delay", f"{draw(st.sampled_from(names))}={value}"]
    return args


def test_csv_files_are_imported_or_refused(tmp_path):
    count = [0]

    @settings(FUZZ, max_examples=CASES)
    @given(csv_files().flatmap(lambda c: st.tuples(st.just(c), options(c[0]))),
           st.sampled_from([[], ["--json"]]))
    def case(drawn, json_flag):
        count[0] += 1
        (_, data), args = drawn
        source = tmp_path / "data.csv"
        source.write_bytes(data)
        out = tmp_path / f"imported-{count[0]}.h5"
        code = check_command(["import", str(source), "-o", str(out), *args, *json_flag],
                             named=[str(source), "--rate", "--reference", "--delay"],
                             inputs=[source], outputs=[out])
        if code == 0:  # what was written is a run file fsi-lab reads back
            run = read_run(out)
            assert run.channels and all(c.data.size >= 2 for c in run.channels.values())
            out.unlink()

    case()
    tally("CSV files", count[0], CASES)
