// The pixels of one dispatch (DispatchRange::pixel_list): every pixel of the band, or, in
// adaptive sampling's later passes, the band's entries of the pixel list. Needs `range`,
// `frame` and the kernel's `pixel_list` binding. CPU twin: src/cpu/pixel_list.rs.

uint dispatch_pixels() {
    return range.pixel_list == NO_PIXEL_LIST ? range.row_count * frame.width : range.pixel_count;
}

// The band-relative index of the dispatch's i-th pixel.
uint dispatch_pixel(uint i) {
    return range.pixel_list == NO_PIXEL_LIST ? i : pixel_list[range.pixel_list + i] - range.row_begin * frame.width;
}
