//! Typed dispatch, as rust-analyzer's `RequestDispatcher` does it: each handler is
//! registered for an `lsp_types` request or notification type, which fixes its
//! method name and its parameter and result types. Requests have one error path:
//! parameters that do not parse get `InvalidParams`, a handler's [`Failure`] its own
//! code, and a method no handler took `MethodNotFound`.

use lsp_server::{ErrorCode, Notification, Request, RequestId, Response};
use lsp_types::notification::Notification as NotificationType;
use lsp_types::request::Request as RequestType;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Why a request got no result.
#[derive(Debug)]
pub(super) struct Failure {
    pub code: ErrorCode,
    pub message: String,
}

impl Failure {
    pub fn new(code: ErrorCode, message: impl Into<String>) -> Failure {
        Failure {
            code,
            message: message.into(),
        }
    }

    /// A request that was understood but cannot be carried out (`RequestFailed`).
    pub fn failed(message: impl Into<String>) -> Failure {
        Failure::new(ErrorCode::RequestFailed, message)
    }
}

/// The response to a request with `id`: its result, or its failure.
pub(super) fn respond<T: Serialize>(id: RequestId, result: Result<T, Failure>) -> Response {
    match result {
        Ok(value) => Response::new_ok(id, value),
        Err(f) => Response::new_err(id, f.code as i32, f.message),
    }
}

/// Hands a request to the handler registered for its method.
pub(super) struct RequestDispatcher<'a, S> {
    req: Option<Request>,
    state: &'a S,
    response: Option<Response>,
}

impl<'a, S> RequestDispatcher<'a, S> {
    pub fn new(req: Request, state: &'a S) -> Self {
        RequestDispatcher {
            req: Some(req),
            state,
            response: None,
        }
    }

    /// Answers the request with `handler` if it is an `R`.
    pub fn on<R>(&mut self, handler: fn(&S, R::Params) -> Result<R::Result, Failure>) -> &mut Self
    where
        R: RequestType,
        R::Params: DeserializeOwned,
        R::Result: Serialize,
    {
        let Some(req) = self.req.take_if(|r| r.method == R::METHOD) else {
            return self;
        };
        let result = serde_json::from_value::<R::Params>(req.params)
            .map_err(|e| Failure::new(ErrorCode::InvalidParams, e.to_string()))
            .and_then(|params| handler(self.state, params));
        self.response = Some(respond(req.id, result));
        self
    }

    /// The response, or `MethodNotFound` when no handler took the request.
    pub fn finish(&mut self) -> Response {
        if let Some(r) = self.response.take() {
            return r;
        }
        let req = self.req.take().expect("a request is answered once");
        respond::<()>(
            req.id,
            Err(Failure::new(
                ErrorCode::MethodNotFound,
                format!("sdfc does not handle {}", req.method),
            )),
        )
    }
}

/// Hands a notification to the handler registered for its method. There is no one to
/// answer: notifications with parameters that do not parse, and unknown ones, are
/// dropped.
pub(super) struct NotificationDispatcher<'a, S> {
    note: Option<Notification>,
    state: &'a mut S,
}

impl<'a, S> NotificationDispatcher<'a, S> {
    pub fn new(note: Notification, state: &'a mut S) -> Self {
        NotificationDispatcher {
            note: Some(note),
            state,
        }
    }

    /// Runs `handler` if the notification is an `N` with valid parameters.
    pub fn on<N, E>(
        &mut self,
        handler: fn(&mut S, N::Params) -> Result<(), E>,
    ) -> Result<&mut Self, E>
    where
        N: NotificationType,
        N::Params: DeserializeOwned,
    {
        let Some(note) = self.note.take_if(|n| n.method == N::METHOD) else {
            return Ok(self);
        };
        if let Ok(params) = serde_json::from_value::<N::Params>(note.params) {
            handler(self.state, params)?;
        }
        Ok(self)
    }
}
