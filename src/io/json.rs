//! Strict JSON input for scene and camera files: the whole text must be one value, and an error
//! says where, as the JSON path of the offending field or, for a syntax error, its line.

use serde::de::DeserializeOwned;

/// Parses `text` as one `T`. On failure returns (location, message): the field's JSON path
/// (`cloths[0].remesh.size`), `JSON` for the document as a whole, or `line N` for a syntax
/// error or text after the value (the column is in the message).
pub fn parse<T: DeserializeOwned>(text: &str) -> Result<T, (String, String)> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let value: T = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.inner();
        let loc = if inner.is_syntax() || inner.is_eof() {
            format!("line {}", inner.line())
        } else if path == "." {
            "JSON".to_string()
        } else {
            path
        };
        (loc, inner.to_string())
    })?;
    de.end().map_err(|e| (format!("line {}", e.line()), e.to_string()))?;
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    struct T {
        #[allow(dead_code)]
        a: Vec<u32>,
    }

    #[test]
    fn errors_name_the_field_or_the_line() {
        assert!(parse::<T>(r#"{"a": [1, 2]}"#).is_ok());
        assert_eq!(parse::<T>(r#"{"a": [1, -2]}"#).unwrap_err().0, "a[1]");
        assert_eq!(parse::<T>(r#"{"a": [1], "b": 0}"#).unwrap_err().0, "b");
        assert_eq!(parse::<T>("{}").unwrap_err().0, "JSON");
        assert_eq!(parse::<T>("{\n\"a\": [1,]}").unwrap_err().0, "line 2");
        assert_eq!(parse::<T>("{\"a\": []}\nx").unwrap_err().0, "line 2");
    }
}
