//! The HTTP API's guards, as axum middleware: an instance-wide rate limit (429 with
//! `Retry-After`), a request body size limit (413) and the bearer token that every non-GET
//! request must present (401 when absent or wrong, 403 when the service has no token at all,
//! which makes a fresh install read-only by default).
//!
//! The token is compared in constant time; it never reaches a log line (the config holds it as
//! a [`Secret`]).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use axum::extract::{Request, State};
use axum::http::{HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::config::{HttpConfig, Secret, TOKEN_ENV};
use super::http::ApiError;

/// A token bucket: `rate` tokens a second up to `burst`; each request takes one.
#[derive(Debug)]
pub struct RateLimiter {
    rate: f64,
    burst: f64,
    state: Mutex<(f64, Instant)>,
}

impl RateLimiter {
    /// A full bucket. `rate` 0 (or less) means no limit.
    pub fn new(rate: f64, burst: u32) -> Self {
        let burst = f64::from(burst.max(1));
        Self { rate, burst, state: Mutex::new((burst, Instant::now())) }
    }

    /// Takes a token at `now`; `Err(seconds)` says how long until one is there.
    pub fn take(&self, now: Instant) -> Result<(), f64> {
        if self.rate <= 0.0 {
            return Ok(());
        }
        // Plain data: a poisoned lock is still consistent.
        let mut st = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let elapsed = now.saturating_duration_since(st.1).as_secs_f64();
        st.0 = (st.0 + elapsed * self.rate).min(self.burst);
        st.1 = now;
        if st.0 >= 1.0 {
            st.0 -= 1.0;
            Ok(())
        } else {
            Err((1.0 - st.0) / self.rate)
        }
    }
}

/// What the middleware needs, built once from the config.
#[derive(Debug)]
pub struct Guard {
    token: Option<Secret>,
    max_body: usize,
    limiter: RateLimiter,
}

impl Guard {
    /// From the HTTP config and the resolved token (see [`HttpConfig::resolve_token`]).
    pub fn new(cfg: &HttpConfig, token: Option<Secret>) -> Self {
        Self {
            token,
            max_body: cfg.max_body_bytes,
            limiter: RateLimiter::new(cfg.rate_limit_per_s, cfg.rate_limit_burst),
        }
    }

    /// Largest body accepted, bytes.
    pub fn max_body(&self) -> usize {
        self.max_body
    }
}

/// Equality whose time does not depend on where the inputs differ (`subtle`'s constant-time
/// comparison; it does depend on their lengths, which tells an attacker nothing useful about a
/// random token).
pub fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    use subtle::ConstantTimeEq;
    bool::from(a.ct_eq(b))
}

/// The rate limit, outermost: it also shields the token check from guessing at full speed.
pub async fn rate_limit(State(g): State<Arc<Guard>>, req: Request, next: Next) -> Response {
    match g.limiter.take(Instant::now()) {
        Ok(()) => next.run(req).await,
        Err(wait) => {
            let secs = wait.ceil().max(1.0) as u64;
            let mut r = ApiError::new(
                StatusCode::TOO_MANY_REQUESTS,
                format!("rate limit exceeded; retry in {secs} s (http.rate_limit_per_s)"),
            )
            .into_response();
            r.headers_mut().insert(header::RETRY_AFTER, HeaderValue::from(secs));
            r
        }
    }
}

/// Refuses a declared body larger than the limit before anything reads it; bodies without a
/// length are cut by axum's `DefaultBodyLimit` in the extractors.
pub async fn body_limit(State(g): State<Arc<Guard>>, req: Request, next: Next) -> Response {
    let declared = req
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok());
    if declared.is_some_and(|n| n > g.max_body as u64) {
        return too_large(g.max_body);
    }
    next.run(req).await
}

/// The 413 answer.
pub fn too_large(max: usize) -> Response {
    ApiError::new(
        StatusCode::PAYLOAD_TOO_LARGE,
        format!("request body larger than {max} bytes (http.max_body_bytes)"),
    )
    .into_response()
}

/// GET and HEAD pass; anything else needs `Authorization: Bearer <token>`.
pub async fn require_token(State(g): State<Arc<Guard>>, req: Request, next: Next) -> Response {
    if req.method() == Method::GET || req.method() == Method::HEAD {
        return next.run(req).await;
    }
    let Some(token) = &g.token else {
        return ApiError::new(
            StatusCode::FORBIDDEN,
            format!(
                "{} {} needs an API token, and none is configured: set http.token_env in the \
                 config to the name of an environment variable holding a token of at least 16 \
                 characters, or set {TOKEN_ENV}; then send Authorization: Bearer <token>",
                req.method(),
                req.uri().path()
            ),
        )
        .into_response();
    };
    let presented = req
        .headers()
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::trim);
    match presented {
        Some(p) if constant_time_eq(p.as_bytes(), token.expose().as_bytes()) => next.run(req).await,
        _ => {
            tracing::warn!(method = %req.method(), path = req.uri().path(), "request refused: missing or wrong bearer token");
            let mut r = ApiError::new(
                StatusCode::UNAUTHORIZED,
                "missing or wrong bearer token (Authorization: Bearer <token>)".into(),
            )
            .into_response();
            r.headers_mut().insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
            r
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn the_bucket_refills_at_its_rate() {
        let l = RateLimiter::new(10.0, 3);
        let t0 = Instant::now();
        assert!((0..3).all(|_| l.take(t0).is_ok()));
        let wait = l.take(t0).unwrap_err();
        assert!((wait - 0.1).abs() < 1e-9, "{wait}");
        assert!(l.take(t0 + Duration::from_millis(100)).is_ok());
        assert!(l.take(t0 + Duration::from_millis(100)).is_err());
        assert!(RateLimiter::new(0.0, 1).take(t0).is_ok(), "rate 0 is no limit");
    }

    #[test]
    fn tokens_compare_by_content() {
        assert!(constant_time_eq(b"abc", b"abc"));
        assert!(!constant_time_eq(b"abc", b"abd"));
        assert!(!constant_time_eq(b"abc", b"abcd"));
    }
}
