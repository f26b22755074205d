//! A headless Chromium driven through the DevTools protocol, for the viewer test
//! ([`crate::viewer`]).
//!
//! The browser is started with `--remote-debugging-pipe`: it reads protocol messages (JSON,
//! each ended by a NUL byte) on its file descriptor 3 and writes them on 4. The standard
//! library cannot hand a child arbitrary descriptors without `unsafe`, so `sh` does it: our
//! pipe to the child's standard input becomes its 3 and the pipe from its standard output its
//! 4. No WebSocket, no port, no client crate: the few commands the test needs (open a page,
//! evaluate an expression, dispatch a mouse event, take a screenshot) are a dozen lines of
//! JSON. Every console error, uncaught exception and error-level log entry of the page is
//! collected ([`Browser::errors`]).
//!
//! WebGL runs on SwiftShader (ANGLE's software renderer): a CI machine has no GPU.

use std::io::{BufRead as _, BufReader, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

use base64::Engine as _;
use serde_json::{Value, json};

use crate::Result;

/// How long one protocol command may take before the test gives up.
const COMMAND_TIMEOUT: Duration = Duration::from_secs(60);

/// The Chromium program: `$CHROMIUM`, which `cargo xtask` sets to the program it found or
/// installed (`xtask/launcher`, which owns the list of prerequisites and where to look).
///
/// # Errors
/// `CHROMIUM` is not set (xtask was run without the launcher), with what to run instead.
pub fn find() -> Result<PathBuf> {
    match std::env::var_os("CHROMIUM") {
        Some(p) if !p.is_empty() => Ok(PathBuf::from(p)),
        _ => Err(
            "CHROMIUM is not set: run the viewer test as `cargo xtask viewer` (or `cargo \
                  xtask ci`), which finds Chromium or installs it and says how to get it \
                  when it cannot, or set CHROMIUM to the program"
                .to_owned(),
        ),
    }
}

/// A running headless browser with one page open.
pub struct Browser {
    child: Child,
    to: ChildStdin,
    from: Receiver<Value>,
    next_id: u64,
    session: String,
    events: Vec<Value>,
    errors: Vec<String>,
}

/// An RGBA image (8 bits per channel, rows top to bottom).
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `4 × width × height` bytes.
    pub rgba: Vec<u8>,
}

impl Image {
    /// The pixel at column `x`, row `y` (from the top left), or `None` outside.
    pub fn at(&self, x: i64, y: i64) -> Option<[u8; 4]> {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return None;
        }
        let i = 4 * (y as usize * self.width + x as usize);
        Some([
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ])
    }
}

impl Browser {
    /// Starts `program` headless with a `width` × `height` CSS-pixel page, its profile and
    /// log in `scratch` (emptied first).
    ///
    /// # Errors
    /// The browser does not start or does not answer.
    pub fn start(program: &Path, scratch: &Path, width: u32, height: u32) -> Result<Self> {
        let _ = std::fs::remove_dir_all(scratch);
        std::fs::create_dir_all(scratch)
            .map_err(|e| format!("cannot create {}: {e}", scratch.display()))?;
        let log = std::fs::File::create(scratch.join("chromium.log"))
            .map_err(|e| format!("cannot create the browser's log: {e}"))?;
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(r#"exec "$0" "$@" 3<&0 4>&1 0</dev/null 1>/dev/null"#)
            .arg(program)
            .args([
                "--headless",
                "--remote-debugging-pipe",
                // The test opens only its own local pages; CI runs as root, where Chromium's
                // sandbox cannot start.
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--no-first-run",
                "--no-default-browser-check",
                "--disable-extensions",
                "--hide-scrollbars",
                "--mute-audio",
                &format!("--window-size={width},{height}"),
                &format!("--user-data-dir={}", scratch.join("profile").display()),
                "about:blank",
            ])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(log)
            .spawn()
            .map_err(|e| format!("cannot start {}: {e}", program.display()))?;
        let to = child.stdin.take().ok_or("no pipe to the browser")?;
        let stdout = child.stdout.take().ok_or("no pipe from the browser")?;
        let (send, from) = channel();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(stdout);
            let mut message = Vec::new();
            while reader.read_until(0, &mut message).is_ok_and(|n| n > 0) {
                if message.last() == Some(&0) {
                    message.pop();
                }
                if let Ok(v) = serde_json::from_slice::<Value>(&message) {
                    if send.send(v).is_err() {
                        break;
                    }
                }
                message.clear();
            }
        });
        let mut browser = Self {
            child,
            to,
            from,
            next_id: 0,
            session: String::new(),
            events: Vec::new(),
            errors: Vec::new(),
        };
        let target = browser.call("Target.createTarget", json!({"url": "about:blank"}))?;
        let target = target["targetId"].clone();
        let attached = browser.call(
            "Target.attachToTarget",
            json!({"targetId": target, "flatten": true}),
        )?;
        browser.session = attached["sessionId"]
            .as_str()
            .ok_or("no session from Target.attachToTarget")?
            .to_owned();
        for domain in ["Page.enable", "Runtime.enable", "Log.enable"] {
            browser.call(domain, json!({}))?;
        }
        browser.call(
            "Emulation.setDeviceMetricsOverride",
            json!({"width": width, "height": height, "deviceScaleFactor": 1, "mobile": false}),
        )?;
        Ok(browser)
    }

    /// Sends `method` with `params` (to the page once attached) and waits for its result.
    ///
    /// # Errors
    /// The browser's error, or no answer within [`COMMAND_TIMEOUT`].
    pub fn call(&mut self, method: &str, params: Value) -> Result<Value> {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({"id": id, "method": method, "params": params});
        if !self.session.is_empty() {
            message["sessionId"] = json!(self.session);
        }
        let mut bytes = serde_json::to_vec(&message).map_err(|e| e.to_string())?;
        bytes.push(0);
        self.to
            .write_all(&bytes)
            .and_then(|()| self.to.flush())
            .map_err(|e| format!("{method}: the browser's pipe closed: {e}"))?;
        let deadline = Instant::now() + COMMAND_TIMEOUT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let v = match self.from.recv_timeout(left) {
                Ok(v) => v,
                Err(RecvTimeoutError::Timeout) => {
                    return Err(format!("{method}: no answer in {COMMAND_TIMEOUT:?}"));
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(format!("{method}: the browser exited"));
                }
            };
            if v["id"].as_u64() == Some(id) {
                if let Some(e) = v.get("error") {
                    return Err(format!("{method}: {e}"));
                }
                return Ok(v["result"].clone());
            }
            self.event(v);
        }
    }

    /// Keeps an event; notes the page's errors.
    fn event(&mut self, v: Value) {
        let p = &v["params"];
        match v["method"].as_str() {
            Some("Runtime.consoleAPICalled")
                if matches!(p["type"].as_str(), Some("error" | "assert")) =>
            {
                let args: Vec<String> = p["args"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|a| a["value"].to_string())
                    .collect();
                self.errors
                    .push(format!("console.error: {}", args.join(" ")));
            }
            Some("Runtime.exceptionThrown") => {
                let d = &p["exceptionDetails"];
                self.errors.push(format!(
                    "uncaught: {} {}",
                    d["text"], d["exception"]["description"]
                ));
            }
            Some("Log.entryAdded") if p["entry"]["level"] == "error" => {
                self.errors.push(format!(
                    "log: {}",
                    p["entry"]["text"].as_str().unwrap_or("")
                ));
            }
            _ => {}
        }
        self.events.push(v);
    }

    /// The page's errors since it was opened (console errors, uncaught exceptions, error log
    /// entries).
    pub fn errors(&self) -> &[String] {
        &self.errors
    }

    /// Opens `url` and waits for its load event.
    ///
    /// # Errors
    /// Navigation fails or the page does not load within [`COMMAND_TIMEOUT`].
    pub fn open(&mut self, url: &str) -> Result<()> {
        self.events.clear();
        self.errors.clear();
        let r = self.call("Page.navigate", json!({"url": url}))?;
        if let Some(e) = r.get("errorText") {
            return Err(format!("cannot open {url}: {e}"));
        }
        let deadline = Instant::now() + COMMAND_TIMEOUT;
        while !self
            .events
            .iter()
            .any(|e| e["method"] == "Page.loadEventFired")
        {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.from.recv_timeout(left) {
                Ok(v) => self.event(v),
                Err(_) => return Err(format!("{url}: no load event in {COMMAND_TIMEOUT:?}")),
            }
        }
        Ok(())
    }

    /// Evaluates `expression` in the page (awaiting a promise) and returns its value.
    ///
    /// # Errors
    /// The expression throws.
    pub fn eval(&mut self, expression: &str) -> Result<Value> {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expression, "returnByValue": true, "awaitPromise": true}),
        )?;
        if let Some(d) = r.get("exceptionDetails") {
            return Err(format!(
                "`{expression}` threw: {} {}",
                d["text"], d["exception"]["description"]
            ));
        }
        Ok(r["result"]["value"].clone())
    }

    /// A left click at CSS pixel (`x`, `y`) of the page: press and release.
    ///
    /// # Errors
    /// The browser refuses the events.
    pub fn click(&mut self, x: f64, y: f64) -> Result<()> {
        for (kind, buttons) in [("mousePressed", 1), ("mouseReleased", 0)] {
            self.call(
                "Input.dispatchMouseEvent",
                json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": buttons, "clickCount": 1}),
            )?;
        }
        Ok(())
    }

    /// A left-button drag from `from` to `to` (CSS pixels) in `steps` moves.
    ///
    /// # Errors
    /// The browser refuses the events.
    pub fn drag(&mut self, from: (f64, f64), to: (f64, f64), steps: u32) -> Result<()> {
        let mouse = |kind: &str, (x, y): (f64, f64), buttons: u32| json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": buttons, "clickCount": 1});
        self.call("Input.dispatchMouseEvent", mouse("mousePressed", from, 1))?;
        for k in 1..=steps {
            let f = f64::from(k) / f64::from(steps);
            let at = (from.0 + f * (to.0 - from.0), from.1 + f * (to.1 - from.1));
            self.call("Input.dispatchMouseEvent", mouse("mouseMoved", at, 1))?;
        }
        self.call("Input.dispatchMouseEvent", mouse("mouseReleased", to, 0))?;
        Ok(())
    }

    /// A wheel turn of `delta_y` (pixels; positive: toward the user) at (`x`, `y`).
    ///
    /// # Errors
    /// The browser refuses the event.
    pub fn wheel(&mut self, x: f64, y: f64, delta_y: f64) -> Result<()> {
        self.call(
            "Input.dispatchMouseEvent",
            json!({"type": "mouseWheel", "x": x, "y": y, "deltaX": 0, "deltaY": delta_y}),
        )?;
        Ok(())
    }

    /// A screenshot of the page, as PNG bytes and decoded.
    ///
    /// # Errors
    /// The browser gives no image or one that does not decode.
    pub fn screenshot(&mut self) -> Result<(Vec<u8>, Image)> {
        let r = self.call("Page.captureScreenshot", json!({"format": "png"}))?;
        let data = r["data"].as_str().ok_or("no screenshot data")?;
        let png = base64::engine::general_purpose::STANDARD
            .decode(data)
            .map_err(|e| format!("screenshot: {e}"))?;
        let image = decode_png(&png)?;
        Ok((png, image))
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        // Browser.close belongs to the browser, not to the page's session.
        self.session.clear();
        let _ = self.call("Browser.close", json!({}));
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Decodes a PNG into 8-bit RGBA.
///
/// # Errors
/// Not a PNG, or a colour type other than RGB or RGBA at 8 bits.
pub fn decode_png(bytes: &[u8]) -> Result<Image> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| format!("png: {e}"))?;
    let mut buf = vec![0; reader.output_buffer_size().ok_or("png: too large")?];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("png: {e}"))?;
    let (width, height) = (info.width as usize, info.height as usize);
    let rgba = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgba, png::BitDepth::Eight) => buf[..4 * width * height].to_vec(),
        (png::ColorType::Rgb, png::BitDepth::Eight) => buf[..3 * width * height]
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        other => return Err(format!("png: unexpected format {other:?}")),
    };
    Ok(Image {
        width,
        height,
        rgba,
    })
}
