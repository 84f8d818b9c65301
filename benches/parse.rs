//! Micro-benchmarks of the per-line hot paths: `cargo bench --bench parse`.
//! Lines per second for each format's common line, wanted and unwanted ids,
//! and for the fallback (full) parsers. The parsers are the library's
//! internals, reached through the `fuzzing` feature's hook.

use std::ops::RangeInclusive;

use divan::{Bencher, black_box};
use emcy_decode::Format;
use emcy_decode::fuzzing::{Detector, Ids, Parser};

fn main() {
    divan::main();
}

/// The ids the decoder wants: EMCY and NMT error control (boot-ups).
const DECODER_IDS: [RangeInclusive<u32>; 2] = [0x81..=0xFF, 0x701..=0x77F];

const LINES: &[(&str, Format, &str)] = &[
    (
        "candump_pdo",
        Format::CandumpLog,
        "(1700000000.123456) can0 181#1122334455667788",
    ),
    (
        "candump_emcy",
        Format::CandumpLog,
        "(1700000000.123456) can0 081#1043090100000000",
    ),
    (
        "candump_padded",
        Format::CandumpLog,
        "(1700000000.123456)  can0 181#11.22.33.44 R",
    ),
    (
        "screen_pdo",
        Format::CandumpScreen,
        " (1700000000.123456)  can0  181   [8]  11 22 33 44 55 66 77 88",
    ),
    (
        "asc_pdo",
        Format::Asc,
        "   3.098426 1  181             Rx   d 8 01 A0 0F A6 60 3B D1 40  Length = 228000 BitCount = 118 ID = 385",
    ),
    (
        "asc_emcy",
        Format::Asc,
        "   3.098426 1  81              Rx   d 8 10 43 09 01 00 00 00 00",
    ),
    (
        "busmaster_pdo",
        Format::Busmaster,
        "22:13:20:1234 Rx 1 0x181 s 8 11 22 33 44 55 66 77 88 ",
    ),
    (
        "busmaster_emcy",
        Format::Busmaster,
        "22:13:20:1234 Rx 1 0x081 s 8 10 43 09 01 00 00 00 00 ",
    ),
    (
        "ixxat_pdo",
        Format::Ixxat,
        "\"00:02:20.66\";\"181\";\"Std\";\"\";\"11 22 33 44 55 66 77 88 \"",
    ),
    (
        "ixxat_emcy",
        Format::Ixxat,
        "\"00:02:20.66\";\"81\";\"Std\";\"\";\"10 43 09 01 00 00 00 00 \"",
    ),
    (
        "screen_annotated",
        Format::CandumpScreen,
        "    (000.000010)  vcan0  603   [8]  A2 7F 7F 00 00 00 00 00   '........' < response",
    ),
    (
        "asc_canfd",
        Format::Asc,
        "  30.005071 CANFD   3 Rx        30a  Generic_Name_12                  1 1 8  8 01 02 03 04 05 06 07 08   102203  133   303000 e0006659 46500250 4b140250 20011736 2001040d",
    ),
];

#[divan::bench(args = LINES.iter().map(|l| l.0))]
fn parse_line(bencher: Bencher, name: &str) {
    let (_, format, line) = LINES.iter().find(|l| l.0 == name).copied().unwrap();
    let mut parser = Parser::new(format, Ids::Standard(&DECODER_IDS));
    bencher
        .counter(divan::counter::BytesCount::new(line.len()))
        .bench_local(|| {
            black_box(parser.parse(black_box(line.as_bytes())));
        });
}

#[divan::bench]
fn detector_locked_candump(bencher: Bencher) {
    let mut d = Detector::auto(Ids::Standard(&DECODER_IDS));
    let line = b"(1700000000.123456) can0 181#1122334455667788";
    d.parse(line);
    bencher.bench_local(|| {
        black_box(d.parse(black_box(line)));
    });
}
