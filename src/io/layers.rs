//! Multi-layer output: one EXR holding every term of a render, and a PNG contact sheet.

use std::path::Path;

use super::image::{Image, ImageError};

/// Writes the named images as the layers of one EXR (`<name>.R`, `<name>.G`, `<name>.B`),
/// atomically. Readers that take the first layer get the first image given.
pub fn write_layers_exr(path: &Path, layers: &[(&str, &Image)]) -> Result<(), ImageError> {
    write_layers_exr_with(path, layers, Vec::new())
}

/// `write_layers_exr` with extra attributes (name, value), stored in every layer's header.
pub fn write_layers_exr_with(
    path: &Path,
    layers: &[(&str, &Image)],
    attributes: Vec<(&str, exr::meta::attribute::AttributeValue)>,
) -> Result<(), ImageError> {
    use exr::prelude::*;
    let (w, h) = layers.first().map_or((0, 0), |(_, i)| (i.width as usize, i.height as usize));
    let exr_layers: Vec<Layer<AnyChannels<FlatSamples>>> = layers
        .iter()
        .map(|(name, image)| {
            let channel = |c: usize| FlatSamples::F32(image.pixels.iter().map(|p| p[c]).collect());
            let channels = AnyChannels::sort(
                vec![
                    AnyChannel::new("R", channel(0)),
                    AnyChannel::new("G", channel(1)),
                    AnyChannel::new("B", channel(2)),
                ]
                .into(),
            );
            let mut layer_attributes = LayerAttributes::named(*name);
            // Custom attributes live in each layer's header: EXR keeps image-wide ones only for
            // standard fields.
            for (key, value) in &attributes {
                layer_attributes.other.insert(exr::meta::attribute::Text::from(*key), value.clone());
            }
            // Increasing line order: the parallel compressor then writes blocks in a fixed order, so
            // identical images give identical bytes (the default order is whatever finishes first).
            let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
            Layer::new((w, h), layer_attributes, encoding, channels)
        })
        .collect();
    let image =
        exr::image::Image::from_layers(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))), exr_layers);
    super::image::write_atomically(path, |tmp| image.write().to_file(tmp).map_err(|e| e.to_string()))
}

/// The images side by side, left to right, with a 4-pixel black gap between them.
pub fn contact_sheet(images: &[&Image]) -> Image {
    const GAP: u32 = 4;
    let (w, h) = images.first().map_or((0, 0), |i| (i.width, i.height));
    let n = images.len() as u32;
    let mut sheet = Image::new(n * w + n.saturating_sub(1) * GAP, h);
    for (k, image) in images.iter().enumerate() {
        let x0 = k as u32 * (w + GAP);
        for y in 0..h {
            for x in 0..w {
                sheet.pixels[(y * sheet.width + x0 + x) as usize] = image.pixel(x, y);
            }
        }
    }
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layered_exr_holds_every_layer() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("layers.exr");
        let mut a = Image::new(4, 3);
        a.pixels[5] = [1.0, 2.0, 3.0];
        let mut b = Image::new(4, 3);
        b.pixels[7] = [0.5, 0.25, 0.125];
        write_layers_exr(&path, &[("combined", &a), ("direct", &b)]).unwrap();
        let read = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
        let names: Vec<String> =
            read.layer_data.iter().map(|l| l.attributes.layer_name.as_ref().unwrap().to_string()).collect();
        assert_eq!(names, ["combined", "direct"]);
        // The first layer reads back as the plain image.
        assert_eq!(super::super::read_exr(&path).unwrap(), a);
    }
}
