//! Sizes declared in file headers (issue 27, item 4): overflow-checked, compared with the
//! file's length, held to the memory budget, before anything is allocated. Each case is a
//! file's exact bytes; each asserts the error and that no allocation larger than
//! [`SMALL`] was asked for on the way (a reservation the kernel never backs is invisible
//! in the resident size, so this test binary counts requests itself).
#![allow(unsafe_code)] // The counting allocator below: `GlobalAlloc` is an unsafe trait.

use bodyseg_io::{
    IoError, MAX_DECLARED_BYTES, MAX_DECLARED_POINTS, MAX_IMAGE_SIDE_PX, parse_depth_png,
    parse_label_png, parse_mat_matrix, parse_mat_variable_names, parse_pcd, parse_ply,
    parse_rgb_image,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;

/// Largest single allocation a rejected hostile file may cause: 1 MiB (the files are a
/// few hundred bytes; their headers declare gigabytes).
const SMALL: usize = 1 << 20;

thread_local! {
    /// Largest allocation request on this thread since [`largest_allocation`] last reset
    /// it (tests run on threads of their own).
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

/// The system allocator, noting each thread's largest request.
struct Counting;

// SAFETY: forwards every call to `System` unchanged; the note is a thread-local `Cell`
// with a const initialiser, which neither allocates nor registers a destructor.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's layout, forwarded.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's layout, forwarded.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: `ptr` came from `System` with `layout`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn note(size: usize) {
    let _ = LARGEST.try_with(|l| l.set(l.get().max(size)));
}

/// Runs `f` and returns its result with the largest allocation it asked for.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|l| l.set(0));
    let out = f();
    (out, LARGEST.with(Cell::get))
}

/// `f` fails with an error whose message holds `needle`, asking for at most [`SMALL`]
/// bytes at once.
fn assert_refused<T: std::fmt::Debug>(f: impl FnOnce() -> Result<T, IoError>, needle: &str) {
    let (result, largest) = largest_allocation(f);
    assert!(
        largest <= SMALL,
        "asked for {largest} bytes at once ({result:?})"
    );
    let err = result
        .expect_err("hostile sizes must be refused")
        .to_string();
    assert!(err.contains(needle), "{needle:?} not in {err:?}");
}

fn pcd_header(
    fields: &str,
    size: &str,
    ty: &str,
    count: &str,
    points: &str,
    data: &str,
) -> Vec<u8> {
    format!(
        "FIELDS {fields}\nSIZE {size}\nTYPE {ty}\nCOUNT {count}\nWIDTH {points}\nHEIGHT 1\nPOINTS {points}\nDATA {data}\n"
    )
    .into_bytes()
}

/// The case: a 134-byte `binary_compressed` PCD whose header declares 300 million
/// points (3.6 GB uncompressed) reserved that much before decompressing 14 bytes.
#[test]
fn pcd_134_byte_binary_compressed_reserves_nothing_large() {
    let mut bytes = b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 300000000\nHEIGHT 1\nPOINTS 300000000\nDATA binary_compressed\n".to_vec();
    bytes.extend_from_slice(&14u32.to_le_bytes()); // compressed size
    bytes.extend_from_slice(&3_600_000_000u32.to_le_bytes()); // uncompressed: 12 x 300M
    bytes.push(12); // LZF literal run of 13 bytes
    bytes.extend_from_slice(&[0; 13]);
    assert_eq!(bytes.len(), 134);
    assert_refused(
        || parse_pcd(&bytes, Path::new("hostile.pcd")),
        "cannot hold 3600000000 bytes (LZF expands at most 88x)",
    );
}

/// `binary_compressed` sizes that disagree with the file: a compressed block longer than
/// the file, and one that claims to expand beyond what LZF can.
#[test]
fn pcd_compressed_sizes_are_checked_against_the_file() {
    // 1000 points of 12 bytes, then the sizes prefix (compressed, uncompressed) and data.
    let file = |compressed: u32, uncompressed: u32, data: &[u8]| {
        let mut bytes = pcd_header(
            "x y z",
            "4 4 4",
            "F F F",
            "1 1 1",
            "1000",
            "binary_compressed",
        );
        bytes.extend_from_slice(&compressed.to_le_bytes());
        bytes.extend_from_slice(&uncompressed.to_le_bytes());
        bytes.extend_from_slice(data);
        bytes
    };
    let long = file(u32::MAX, 12_000, &[0; 16]);
    assert_refused(
        || parse_pcd(&long, Path::new("long.pcd")),
        "compressed block of 4294967295 bytes, file holds 16",
    );
    let bomb = file(2, 12_000, &[0, 0]);
    assert_refused(
        || parse_pcd(&bomb, Path::new("bomb.pcd")),
        "compressed block of 2 bytes cannot hold 12000 bytes",
    );
}

/// A `COUNT` so large that one point's size overflows: the product wrapped (release) or
/// panicked (debug) before; now a header error.
#[test]
fn pcd_huge_count_is_a_header_error() {
    for data in ["ascii", "binary", "binary_compressed"] {
        let bytes = pcd_header(
            "x y z",
            "4 4 8",
            "F F F",
            "1 1 2305843009213693952",
            "1",
            data,
        );
        assert_refused(
            || parse_pcd(&bytes, Path::new("count.pcd")),
            "field 'z' has COUNT 2305843009213693952",
        );
    }
}

/// `POINTS` beyond the budget, or whose data would, are refused in the header, whatever
/// the data kind. 2⁶² points of 12 bytes wrapped to 0 bytes, and the compressed reader
/// then indexed past its (empty) buffer: a panic.
#[test]
fn pcd_huge_points_are_refused_in_the_header() {
    let too_many = MAX_DECLARED_POINTS + 1;
    let wraps = 1u64 << 62;
    for data in ["ascii", "binary", "binary_compressed"] {
        for points in [too_many, wraps, u64::MAX] {
            let mut bytes = pcd_header(
                "x y z",
                "4 4 4",
                "F F F",
                "1 1 1",
                &points.to_string(),
                data,
            );
            bytes.extend_from_slice(&[0; 8]);
            assert_refused(
                || parse_pcd(&bytes, Path::new("points.pcd")),
                "is more than bodyseg reads",
            );
        }
        // Few enough points, too many bytes: 2^29 points of 3 doubles are 12 GiB.
        let bytes = pcd_header("x y z", "8 8 8", "F F F", "1 1 1", "536870912", data);
        assert_refused(
            || parse_pcd(&bytes, Path::new("bytes.pcd")),
            &format!("more data than bodyseg reads ({MAX_DECLARED_BYTES} bytes)"),
        );
    }
}

/// A binary PCD that declares more points than its data holds is refused from the file's
/// length (no allocation for the declared points).
#[test]
fn pcd_binary_points_are_checked_against_the_file_length() {
    let mut bytes = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", "100000000", "binary");
    bytes.extend_from_slice(&[0; 24]);
    assert_refused(
        || parse_pcd(&bytes, Path::new("short.pcd")),
        "header declares 100000000 points of 12 bytes (1200000000 bytes), data holds 24 bytes",
    );
}

/// PLY element counts and list lengths far beyond the data: bounded by the file's length.
#[test]
fn ply_huge_counts_are_bounded_by_the_file() {
    let binary = b"ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\nproperty float x\nproperty float y\nproperty float z\nproperty uchar label\nend_header\n\0\0\0\0";
    assert_refused(
        || parse_ply(binary, Path::new("count.ply")),
        "declares 18446744073709551615",
    );
    let ascii = b"ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nproperty uchar label\nend_header\n0 0 0 0\n";
    assert_refused(
        || parse_ply(ascii, Path::new("ascii.ply")),
        "declares 4000000000",
    );
    let list = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty uchar label\nproperty list uint uint junk\nend_header\n\0\0\0\0\0\0\0\0\0\0\0\0\0\xff\xff\xff\xff";
    assert_refused(|| parse_ply(list, Path::new("list.ply")), "vertex");
}

/// A little-endian MAT v5 file holding one uncompressed `miMATRIX` element of `body`.
fn mat_file(body: &[u8]) -> Vec<u8> {
    let mut f = b"MATLAB 5.0 MAT-file".to_vec();
    f.resize(116, b' ');
    f.extend_from_slice(&[0; 8]);
    f.extend_from_slice(&0x0100u16.to_le_bytes());
    f.extend_from_slice(b"IM");
    f.extend_from_slice(&14u32.to_le_bytes());
    f.extend_from_slice(&(body.len() as u32).to_le_bytes());
    f.extend_from_slice(body);
    f
}

fn le(v: u32) -> [u8; 4] {
    v.to_le_bytes()
}

/// The flags, dimensions (`rows × cols`, int32) and name `a` of a `uint8` array.
fn mat_array_header(rows: i32, cols: i32) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(&le(6)); // miUINT32 flags
    b.extend_from_slice(&le(8));
    b.extend_from_slice(&le(9)); // mxUINT8_CLASS
    b.extend_from_slice(&le(0));
    b.extend_from_slice(&le(5)); // miINT32 dims
    b.extend_from_slice(&le(8));
    b.extend_from_slice(&rows.to_le_bytes());
    b.extend_from_slice(&cols.to_le_bytes());
    b.extend_from_slice(&(1u32 | (1 << 16)).to_le_bytes()); // small miINT8 name, 1 byte
    b.extend_from_slice(&[b'a', 0, 0, 0]);
    b
}

/// A matrix whose values as f64 exceed the budget is refused from its dimensions, before
/// its data is read.
#[test]
fn mat_dimensions_beyond_the_budget_are_refused() {
    let mut body = mat_array_header(i32::MAX, i32::MAX);
    body.extend_from_slice(&le(2)); // miUINT8 data, 4 bytes declared
    body.extend_from_slice(&le(4));
    body.extend_from_slice(&[1, 2, 3, 4, 0, 0, 0, 0]);
    let file = mat_file(&body);
    assert_refused(
        || parse_mat_matrix(&file, "a", Path::new("big.mat")),
        &format!(
            "is too large (2147483647x2147483647: more than {MAX_DECLARED_BYTES} bytes as f64)"
        ),
    );
}

/// A data element whose declared length disagrees with the dimensions is refused before
/// it is read (a compressed one could inflate to 4 GiB).
#[test]
fn mat_data_length_is_checked_against_the_dimensions() {
    let mut body = mat_array_header(2, 3);
    body.extend_from_slice(&le(2)); // miUINT8, 4 GiB - 8 declared
    body.extend_from_slice(&le(u32::MAX - 7));
    body.extend_from_slice(&[0; 8]);
    let file = mat_file(&body);
    assert_refused(
        || parse_mat_matrix(&file, "a", Path::new("len.mat")),
        "variable 'a' is 2x3 (6 values) but holds 4294967288 values",
    );
}

/// Array header sub-elements (flags, dimensions, name) are small: a huge declared one is
/// refused before it is read.
#[test]
fn mat_huge_array_name_is_refused() {
    let mut body = mat_array_header(1, 1);
    body.truncate(body.len() - 8);
    body.extend_from_slice(&le(1)); // miINT8 name of 2 GiB
    body.extend_from_slice(&le(1 << 31));
    body.extend_from_slice(b"abcdefgh");
    let file = mat_file(&body);
    assert_refused(
        || parse_mat_variable_names(&file, Path::new("name.mat")),
        "array name element of 2147483648 bytes (at most 65536)",
    );
}

/// A 0 × 2³¹−1 matrix is empty: read at once, not by walking two billion empty columns.
#[test]
fn mat_empty_matrix_with_huge_width_reads_at_once() {
    let mut body = mat_array_header(0, i32::MAX);
    body.extend_from_slice(&le(2));
    body.extend_from_slice(&le(0));
    let file = mat_file(&body);
    let start = std::time::Instant::now();
    let m = parse_mat_matrix(&file, "a", Path::new("empty.mat")).expect("an empty matrix");
    assert_eq!((m.rows, m.cols, m.values.len()), (0, i32::MAX as usize, 0));
    // Generous: the fixed reader takes microseconds; walking the columns takes seconds
    // in release and minutes in debug.
    assert!(start.elapsed().as_secs_f64() < 0.5, "{:?}", start.elapsed());
}

/// The PNG signature and an IHDR chunk of `width × height`, 16-bit grayscale, with its
/// CRC (the decoder reads the header before any pixel data).
fn png_header(width: u32, height: u32, bit_depth: u8) -> Vec<u8> {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[bit_depth, 0, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend_from_slice(&13u32.to_be_bytes());
    png.extend_from_slice(&ihdr);
    png.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    png
}

/// CRC-32 (ISO 3309, as PNG uses), bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = u32::MAX;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A PNG header wider or higher than [`MAX_IMAGE_SIDE_PX`], or declaring gigabytes, is
/// refused from the header by every image reader.
#[test]
fn png_sizes_beyond_the_limits_are_refused_from_the_header() {
    for (w, h) in [
        (MAX_IMAGE_SIDE_PX + 1, 1),
        (1, MAX_IMAGE_SIDE_PX + 1),
        (u32::MAX >> 1, u32::MAX >> 1),
    ] {
        let png = png_header(w, h, 16);
        let at = Path::new("big.png");
        assert_refused(|| parse_depth_png(&png, at), "limit");
        assert_refused(|| parse_label_png(&png_header(w, h, 8), at), "limit");
        assert_refused(|| parse_rgb_image(&png, at), "limit");
    }
}
