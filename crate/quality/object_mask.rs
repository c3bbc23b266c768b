/// The simulator's object colour (a yellow cylinder), lit: yellow pixels have red and green
/// well above blue, which no part of the arm, the table or the background has.
pub const OBJECT_COLOUR: &str = "yellow";

/// Whether an RGB pixel in [0, 1] shows the object: min(r, g) − b > 0.2 and r, g > 0.25.
pub fn is_object(r: f32, g: f32, b: f32) -> bool {
    r > 0.25 && g > 0.25 && r.min(g) - b > 0.2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yellow_is_the_object_and_grey_is_not() {
        assert!(is_object(0.96, 0.86, 0.02));
        assert!(is_object(0.45, 0.40, 0.05), "the shaded side");
        assert!(!is_object(0.53, 0.59, 0.61), "the grey of an average arm");
        assert!(!is_object(0.9, 0.9, 0.9));
        assert!(!is_object(0.1, 0.1, 0.0), "the dark table");
        assert!(!is_object(0.2, 0.3, 0.8), "a blue joint cap");
    }
}
