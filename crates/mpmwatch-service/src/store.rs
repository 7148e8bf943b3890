//! The embedded store: SQLite (bundled) in WAL mode, holding each controller's window rows and
//! the alarm history. With WAL and `synchronous = NORMAL` a committed flush survives a killed
//! process (`kill -9`); only rows closed since the last flush are lost.
//!
//! Blocking: the service calls it from the blocking pool.

use std::path::Path;
use std::sync::Mutex;

use rusqlite::{Connection, params};

use super::alarm::AlarmEvent;
use super::align::WindowRow;

/// A store failure.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// SQLite said no.
    #[error("store: {0}")]
    Sql(#[from] rusqlite::Error),
    /// A stored row does not decode.
    #[error("store: bad stored row: {0}")]
    Decode(#[from] serde_json::Error),
}

/// What the service knows about the store's health: whether its last write succeeded, and the
/// last error. `/healthz` shows it and reports `degraded` while a write fails (a full disk, a
/// file that became unwritable, the size cap reached); the analyses go on meanwhile.
#[derive(Debug, Default)]
pub struct StoreHealth {
    state: Mutex<HealthState>,
}

#[derive(Debug, Default)]
struct HealthState {
    failing: bool,
    errors: u64,
    last_error: Option<String>,
    last_error_time: Option<String>,
    last_ok_time: Option<String>,
}

impl StoreHealth {
    fn state(&self) -> std::sync::MutexGuard<'_, HealthState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A write succeeded at `time`: the store is healthy again.
    pub fn record_ok(&self, time: String) {
        let mut s = self.state();
        s.failing = false;
        s.last_ok_time = Some(time);
    }

    /// A write failed at `time`.
    pub fn record_error(&self, error: String, time: String) {
        let mut s = self.state();
        s.failing = true;
        s.errors += 1;
        s.last_error = Some(error);
        s.last_error_time = Some(time);
    }

    /// Whether the last write failed.
    pub fn failing(&self) -> bool {
        self.state().failing
    }

    /// The `store` object of `/healthz`.
    pub fn snapshot(&self, configured: bool) -> serde_json::Value {
        let s = self.state();
        serde_json::json!({
            "configured": configured,
            "ok": !s.failing,
            "errors": s.errors,
            "error": s.last_error,
            "last_error_time": s.last_error_time,
            "last_ok_time": s.last_ok_time,
        })
    }
}

/// The SQLite store.
pub struct Store {
    conn: Mutex<Connection>,
}

fn encode(v: &[f64]) -> String {
    // NaN (an absent MV) becomes null.
    serde_json::to_string(&v.iter().map(|x| x.is_finite().then_some(*x)).collect::<Vec<_>>())
        .unwrap_or_else(|_| "[]".into())
}

fn decode(s: &str) -> Result<Vec<f64>, serde_json::Error> {
    let v: Vec<Option<f64>> = serde_json::from_str(s)?;
    Ok(v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
}

impl Store {
    /// Opens (creating if needed) the database at `path`.
    pub fn open(path: &Path) -> Result<Self, StoreError> {
        if let Some(dir) = path.parent()
            && !dir.as_os_str().is_empty()
        {
            let _ = std::fs::create_dir_all(dir);
        }
        let conn = Connection::open(path)?;
        conn.pragma_update(None, "journal_mode", "WAL")?;
        conn.pragma_update(None, "synchronous", "NORMAL")?;
        conn.busy_timeout(std::time::Duration::from_secs(5))?;
        conn.execute_batch(
            "CREATE TABLE IF NOT EXISTS samples (
                 controller TEXT NOT NULL, slot INTEGER NOT NULL,
                 mv TEXT NOT NULL, dither TEXT NOT NULL, cv TEXT NOT NULL, residual TEXT NOT NULL,
                 PRIMARY KEY (controller, slot)) WITHOUT ROWID;
             CREATE TABLE IF NOT EXISTS alarms (
                 id INTEGER PRIMARY KEY AUTOINCREMENT, controller TEXT NOT NULL, event TEXT NOT NULL,
                 dither TEXT NOT NULL, cv TEXT NOT NULL, time TEXT NOT NULL, json TEXT NOT NULL);
             CREATE INDEX IF NOT EXISTS alarms_by_controller ON alarms (controller, id);",
        )?;
        Ok(Self { conn: Mutex::new(conn) })
    }

    /// Caps the database at about `max_bytes` (SQLite's `max_page_count`): past it every write
    /// fails with "database or disk is full", exactly as on a full disk. Returns the page cap.
    pub fn limit_size(&self, max_bytes: u64) -> Result<u64, StoreError> {
        let conn = self.conn();
        let page: u64 = conn.pragma_query_value(None, "page_size", |r| r.get(0))?;
        let pages = (max_bytes / page.max(1)).max(1);
        let set: u64 = conn.pragma_update_and_check(None, "max_page_count", pages, |r| r.get(0))?;
        Ok(set)
    }

    fn conn(&self) -> std::sync::MutexGuard<'_, Connection> {
        // A panic while holding the lock cannot leave SQLite inconsistent (transactions roll
        // back), so a poisoned lock is still usable.
        self.conn.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Writes rows and forgets rows of `controller` older than `keep_from` slot, in one
    /// transaction; with `replace`, forgets all its stored rows first.
    pub fn save_rows(
        &self,
        controller: &str,
        rows: &[WindowRow],
        keep_from: Option<i64>,
        replace: bool,
    ) -> Result<(), StoreError> {
        let mut conn = self.conn();
        let tx = conn.transaction()?;
        {
            if replace {
                tx.execute("DELETE FROM samples WHERE controller = ?1", params![controller])?;
            }
            let mut ins = tx.prepare_cached(
                "INSERT OR REPLACE INTO samples (controller, slot, mv, dither, cv, residual) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
            )?;
            for r in rows {
                ins.execute(params![
                    controller,
                    r.slot,
                    encode(&r.mv),
                    encode(&r.dither),
                    encode(&r.cv),
                    encode(&r.residual)
                ])?;
            }
            if let Some(k) = keep_from {
                tx.execute(
                    "DELETE FROM samples WHERE controller = ?1 AND slot < ?2",
                    params![controller, k],
                )?;
            }
        }
        tx.commit()?;
        Ok(())
    }

    /// The newest `limit` rows of `controller`, oldest first.
    pub fn load_rows(&self, controller: &str, limit: usize) -> Result<Vec<WindowRow>, StoreError> {
        let conn = self.conn();
        let mut q = conn.prepare(
            "SELECT slot, mv, dither, cv, residual FROM samples WHERE controller = ?1 ORDER BY slot DESC LIMIT ?2",
        )?;
        let raw = q
            .query_map(params![controller, limit as i64], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                    r.get::<_, String>(3)?,
                    r.get::<_, String>(4)?,
                ))
            })?
            .collect::<Result<Vec<_>, _>>()?;
        let mut rows = raw
            .into_iter()
            .map(|(slot, mv, d, cv, e)| {
                Ok(WindowRow {
                    slot,
                    mv: decode(&mv)?,
                    dither: decode(&d)?,
                    cv: decode(&cv)?,
                    residual: decode(&e)?,
                })
            })
            .collect::<Result<Vec<_>, StoreError>>()?;
        rows.reverse();
        Ok(rows)
    }

    /// Appends an alarm event to the history.
    pub fn append_alarm(&self, e: &AlarmEvent) -> Result<(), StoreError> {
        self.conn().execute(
            "INSERT INTO alarms (controller, event, dither, cv, time, json) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
            params![e.controller, e.event.as_str(), e.dither, e.cv, e.time, serde_json::to_string(e)?],
        )?;
        Ok(())
    }

    /// The newest `limit` alarm events of `controller`, oldest first.
    pub fn alarms(&self, controller: &str, limit: usize) -> Result<Vec<AlarmEvent>, StoreError> {
        let conn = self.conn();
        let mut q =
            conn.prepare("SELECT json FROM alarms WHERE controller = ?1 ORDER BY id DESC LIMIT ?2")?;
        let raw = q
            .query_map(params![controller, limit as i64], |r| r.get::<_, String>(0))?
            .collect::<Result<Vec<_>, _>>()?;
        let mut v = raw.iter().map(|s| serde_json::from_str(s)).collect::<Result<Vec<AlarmEvent>, _>>()?;
        v.reverse();
        Ok(v)
    }

    /// Channels (dither, cv) whose last event is a raise.
    pub fn active_alarms(&self, controller: &str) -> Result<Vec<(String, String)>, StoreError> {
        let conn = self.conn();
        let mut q = conn.prepare(
            "SELECT dither, cv, event FROM alarms a WHERE controller = ?1
             AND id = (SELECT MAX(id) FROM alarms b WHERE b.controller = a.controller AND b.dither = a.dither AND b.cv = a.cv)",
        )?;
        let rows = q
            .query_map(params![controller], |r| {
                Ok((r.get::<_, String>(0)?, r.get::<_, String>(1)?, r.get::<_, String>(2)?))
            })?
            .collect::<Result<Vec<_>, _>>()?;
        Ok(rows.into_iter().filter(|(_, _, e)| e == "raise").map(|(d, c, _)| (d, c)).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::alarm::Transition;

    fn row(slot: i64) -> WindowRow {
        WindowRow { slot, mv: vec![f64::NAN], dither: vec![1.0], cv: vec![slot as f64], residual: vec![0.5] }
    }

    fn event(t: Transition) -> AlarmEvent {
        AlarmEvent {
            controller: "c1".into(),
            event: t,
            channel: "ud1→y1".into(),
            mv: "u1".into(),
            dither: "ud1".into(),
            cv: "y1".into(),
            statistic: "norm_mi".into(),
            value_bits: 0.1,
            critical_bits: 0.05,
            p_value: Some(1e-4),
            verdict: "mismatch".into(),
            time: "2026-01-01T00:00:00Z".into(),
            data_time: 10.0,
        }
    }

    #[test]
    fn rows_and_alarms_round_trip_through_a_reopened_file() {
        let dir = std::env::temp_dir().join(format!("mpmwatch-store-{}", std::process::id()));
        let path = dir.join("s.sqlite");
        let _ = std::fs::remove_file(&path);
        {
            let s = Store::open(&path).unwrap();
            s.save_rows("c1", &(0..10).map(row).collect::<Vec<_>>(), None, false).unwrap();
            s.save_rows("c1", &(10..12).map(row).collect::<Vec<_>>(), Some(4), false).unwrap();
            s.append_alarm(&event(Transition::Raise)).unwrap();
        }
        let s = Store::open(&path).unwrap();
        let rows = s.load_rows("c1", 5).unwrap();
        assert_eq!(rows.iter().map(|r| r.slot).collect::<Vec<_>>(), vec![7, 8, 9, 10, 11]);
        assert!(rows[0].mv[0].is_nan());
        assert_eq!(s.load_rows("c1", 100).unwrap().len(), 8);
        assert_eq!(s.active_alarms("c1").unwrap(), vec![("ud1".to_string(), "y1".to_string())]);
        s.append_alarm(&event(Transition::Clear)).unwrap();
        assert!(s.active_alarms("c1").unwrap().is_empty());
        assert_eq!(s.alarms("c1", 10).unwrap().len(), 2);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
